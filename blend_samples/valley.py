"""A valley under snow: a procedural terrain of 1 km × 1 km with a village of houses along its floor and pines on
its slopes (no downloads), snowed with levels of detail from a camera standing on the valley floor, baked and
rendered at 500 × 280. Saves valley.blend next to this script.

blender -b --factory-startup --python blend_samples/valley.py -- [--output out/valley.png] [--width 500]
"""

import math
import os
import random
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sample_common as common  # noqa: E402

SIZE = 1000.0  # m, the terrain's side
CELLS = 160    # terrain quads per side (6.25 m)
SNOW = dict(depth=0.1, spacing=0.05, level_of_detail="ON")  # 1 cm voxels near the camera


def height(x, y):
    """Terrain height (m): a valley along y, rising 80 m to its rims, with rolling hills."""
    return (80.0 * (x / (0.5 * SIZE)) ** 2 + 10.0 * np.sin(y / 90.0) * np.cos(x / 130.0)
            + 3.0 * np.sin(x / 37.0 + y / 53.0))


def mesh_object(name, vertices, faces, mat):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in vertices], [], [tuple(f) for f in faces])
    mesh.update()
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def terrain(mat):
    axis = np.linspace(-0.5 * SIZE, 0.5 * SIZE, CELLS + 1)
    x, y = np.meshgrid(axis, axis, indexing="xy")
    vertices = np.stack([x.ravel(), y.ravel(), height(x, y).ravel()], axis=1)
    n = CELLS + 1
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i) for j in range(CELLS) for i in range(CELLS)]
    return mesh_object("Terrain", vertices, faces, mat)


def boxes(name, specs, mat):
    """One mesh of boxes (centre x, y, base z, size x, y, z, gable roof height): houses with pitched roofs."""
    vertices, faces = [], []
    for cx, cy, z0, sx, sy, sz, roof in specs:
        b = len(vertices)
        hx, hy = 0.5 * sx, 0.5 * sy
        for k, z in enumerate((z0, z0 + sz)):
            vertices += [(cx - hx, cy - hy, z), (cx + hx, cy - hy, z), (cx + hx, cy + hy, z), (cx - hx, cy + hy, z)]
        vertices += [(cx - hx, cy, z0 + sz + roof), (cx + hx, cy, z0 + sz + roof)]  # the ridge, along x
        faces += [(b, b + 3, b + 2, b + 1), (b, b + 1, b + 5, b + 4), (b + 2, b + 3, b + 7, b + 6),
                  (b + 1, b + 2, b + 6, b + 5), (b + 3, b, b + 4, b + 7),
                  (b + 4, b + 5, b + 9, b + 8), (b + 6, b + 7, b + 8, b + 9),  # roof planes
                  (b + 5, b + 6, b + 9), (b + 7, b + 4, b + 8)]  # gables
    return mesh_object(name, vertices, faces, mat)


def pines(name, specs, mat, segments=10):
    """One mesh of cones (x, y, base z, radius, height): pines on the slopes."""
    vertices, faces = [], []
    for x, y, z0, r, h in specs:
        b = len(vertices)
        for s in range(segments):
            a = 2 * math.pi * s / segments
            vertices.append((x + r * math.cos(a), y + r * math.sin(a), z0 + 0.15 * h))
        vertices.append((x, y, z0 + h))
        faces += [(b + s, b + (s + 1) % segments, b + segments) for s in range(segments)]
        faces.append(tuple(b + s for s in reversed(range(segments))))
    return mesh_object(name, vertices, faces, mat)


def build_scene():
    scene = common.new_scene()
    rng = random.Random(16)
    ground = terrain(common.material("Frozen Ground", (0.22, 0.2, 0.16), roughness=0.9))
    houses = []
    for i in range(24):
        x = (-1) ** i * rng.uniform(14.0, 45.0)
        y = -380.0 + i * 28.0 + rng.uniform(-6.0, 6.0)
        z = float(height(x, y)) - 0.5
        houses.append((x, y, z, rng.uniform(7.0, 11.0), rng.uniform(8.0, 12.0), rng.uniform(4.0, 6.0),
                       rng.uniform(2.5, 4.0)))
    village = boxes("Houses", houses, common.material("Timber", (0.35, 0.2, 0.12), roughness=0.8))
    trees = []
    while len(trees) < 400:
        x, y = rng.uniform(-480.0, 480.0), rng.uniform(-480.0, 480.0)
        if abs(x) < 70.0:
            continue  # the village and its road
        trees.append((x, y, float(height(x, y)) - 0.3, rng.uniform(2.0, 3.5), rng.uniform(8.0, 16.0)))
    forest = pines("Pines", trees, common.material("Needles", (0.03, 0.12, 0.05), roughness=0.8))
    common.nishita_sky(scene, sun_elevation_deg=20.0, sun_rotation_deg=150.0)
    common.sun(elevation_deg=20.0, rotation_deg=150.0, irradiance=4.0)
    eye = (3.0, -440.0, float(height(3.0, -440.0)) + 1.7)
    common.camera(location=eye, look_at=(0.0, 0.0, float(height(0.0, 0.0)) + 25.0), lens=35.0)
    return scene, [ground, village, forest]


def volume_bands(snows):
    """The bands that render as volumes (the far ones render as surfaces and need no bake)."""
    return [snow for snow in snows if snow.firn.render_mode != "OPAQUE"]


def main():
    args = common.parse_args(__doc__, "out/valley.png")
    stages = common.Stages()
    scene, targets = stages.run("build scene", build_scene)
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.width * 14 // 25
    bands = stages.run("add snow layer", common.add_snow_bands, targets, **SNOW)
    stages.run("bake scattering", common.bake, volume_bands(bands))
    stages.run("render (Cycles)", common.render, scene, args.output, args.width, args.samples, aspect=(25, 14))
    if not args.no_save:
        stages.run("save .blend", common.save_next_to, __file__, args.blend)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")


if __name__ == "__main__":
    main()
