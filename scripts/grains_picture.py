"""A red ball on grey ground under thin grain snow, rendered by the core's brute-force grain renderer (no Blender):
docs/images/grains_red_ball.png. Chrisman's accumulation, then firncore.grain_radiance under a uniform white sky.

PYTHONPATH=build/python /usr/bin/python3 scripts/grains_picture.py [OUTPUT.png] [--width 240] [--samples 16]
"""

import argparse
import math
import struct
import time
import zlib

import numpy as np

import firncore


def uv_sphere(centre, radius, rings=24, segments=48):
    vertices, triangles = [], []
    for i in range(rings + 1):
        theta = math.pi * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            vertices.append([centre[0] + radius * math.sin(theta) * math.cos(phi),
                             centre[1] + radius * math.sin(theta) * math.sin(phi),
                             centre[2] + radius * math.cos(theta)])
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            if i > 0:
                triangles.append([a, c, b])  # at the poles one of the two has no area: the core would drop it
            if i < rings - 1:
                triangles.append([b, c, d])
    return np.array(vertices, np.float32), np.array(triangles, np.uint32)


def scene():
    s = 0.3  # m, half the ground's side
    ground = np.array([[-s, -s, 0], [s, -s, 0], [s, s, 0], [-s, s, 0]], np.float32)
    ball_v, ball_t = uv_sphere((0.0, 0.0, 0.1), 0.1)
    vertices = np.concatenate([ground, ball_v])
    triangles = np.concatenate([np.array([[0, 1, 2], [0, 2, 3]], np.uint32), ball_t + 4])
    albedo = np.array([[0.5, 0.5, 0.5]] * 2 + [[0.7, 0.04, 0.03]] * len(ball_t))
    return vertices, triangles, albedo


def camera_rays(width, height, eye, target, fov_deg=40.0):
    eye, target = np.array(eye, float), np.array(target, float)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    half = math.tan(math.radians(fov_deg) / 2)
    xs = (np.arange(width) + 0.5) / width * 2 - 1
    ys = 1 - (np.arange(height) + 0.5) / height * 2
    x, y = np.meshgrid(xs * half, ys * half * height / width)
    directions = forward + x[..., None] * right + y[..., None] * up
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    return np.tile(eye, (width * height, 1)), directions.reshape(-1, 3)


def write_png(path, rgb):
    """8-bit sRGB PNG of linear RGB (H, W, 3), without any imaging library."""
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(np.clip(rgb, 0, None), 1 / 2.4) - 0.055)
    pixels = (np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8)
    raw = b"".join(b"\x00" + row.tobytes() for row in pixels)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    height, width = pixels.shape[:2]
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("output", nargs="?", default="docs/images/grains_red_ball.png")
    parser.add_argument("--width", type=int, default=240)
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--grains", type=int, default=60000)
    args = parser.parse_args()
    vertices, triangles, albedo = scene()
    start = time.perf_counter()
    centres, radii, _ = firncore.accumulate_grains(vertices, triangles, count=args.grains, radius=2e-3,
                                                    radius_variation=0.3, seed=1)
    accumulated = time.perf_counter() - start
    width, height = args.width, args.width * 3 // 4
    origins, directions = camera_rays(width, height, eye=(0.55, -0.55, 0.38), target=(0.0, 0.0, 0.07))
    start = time.perf_counter()
    mean, _error = firncore.grain_radiance(centres, radii, origins, directions, vertices=vertices,
                                           triangles=triangles, surface_albedo=albedo, sky=(1.0, 1.0, 1.0),
                                           samples=args.samples, seed=1)
    rendered = time.perf_counter() - start
    write_png(args.output, 0.8 * mean.reshape(height, width, 3))
    print(f"{len(radii)} grains in {accumulated:.1f} s; {width}x{height} px, {args.samples} samples in "
          f"{rendered:.1f} s -> {args.output}")


if __name__ == "__main__":
    main()
