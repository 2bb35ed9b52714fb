"""Does the volume → surface transition show? A 400 m plane under a uniform sky, 10 cm of snow with levels of
detail, seen from 10 m up, pitched so that the boundary between the last volume band (baked) and the first surface
band (white-sky albedo) crosses the middle of a 500 × 280 render. The mean radiance of the snow on each side of
the boundary, in bands of distance, from the render's float pixels (issue 16, item 3: within 3 %).

bench/run.sh bench/far_surface_seam.py -- [--samples 64]
"""

import math
import os
import sys
import tempfile

import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import sample_common as common  # noqa: E402

WIDTH, HEIGHT, EYE = 500, 280, 10.0  # px, px, m above the ground


def ground_distances(camera, top):
    """Per pixel (rows from the bottom, as Blender stores them): the distance (m) from the eye to the snow's top at
    height `top`, or inf where the ray misses it."""
    frame = [camera.matrix_world @ v for v in camera.data.view_frame(scene=bpy.context.scene)]  # tr, br, bl, tl
    eye = camera.matrix_world.translation
    distances = np.full((HEIGHT, WIDTH), np.inf)
    for row in range(HEIGHT):
        v = (row + 0.5) / HEIGHT
        for col in range(WIDTH):
            u = (col + 0.5) / WIDTH
            bottom = frame[2].lerp(frame[1], u)
            point = bottom.lerp(frame[3].lerp(frame[0], u), v)
            d = (point - eye).normalized()
            if d.z < 0.0:
                distances[row, col] = (eye.z - top) / -d.z
    return distances


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    samples = int(argv[argv.index("--samples") + 1]) if "--samples" in argv else 64
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=400.0, location=(0.0, 150.0, 0.0))
    ground = bpy.context.object
    common.overcast_sky(scene, radiance=1.0)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    from firn.common.core import firncore
    probe = common.camera(location=(0.0, -40.0, EYE), look_at=(0.0, 0.0, 0.0), lens=50.0)
    camera_fov = probe.data.angle
    boundary = None
    for level in range(1, 16):  # the first band coarser than half the depth (snow_layer/operators.py)
        if 0.01 * 2 ** level > 0.05:
            boundary = 0.01 * 2 ** level / (camera_fov / WIDTH)
            break
    # Pitch the camera so that the boundary lies in the middle of the picture.
    ground_range = math.sqrt(boundary ** 2 - EYE ** 2)
    probe.rotation_euler = (Vector((0.0, -40.0 + ground_range, 0.1)) - probe.location).to_track_quat("-Z", "Y").to_euler()
    bands = common.add_snow_bands([ground], depth=0.1, spacing=0.05, voxel_size=0.01, level_of_detail="ON")
    volumes = [snow for snow in bands if snow.firn.render_mode != "OPAQUE"]
    common.bake(volumes)
    path = os.path.join(tempfile.mkdtemp(prefix="firn_seam_"), "seam.exr")
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", samples, False
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.empty(WIDTH * HEIGHT * 4, np.float32)
    image.pixels.foreach_get(pixels)
    luminance = pixels.reshape(HEIGHT, WIDTH, 4)[:, :, :3] @ np.array([0.2126, 0.7152, 0.0722])
    distance = ground_distances(scene.camera, 0.1)
    print(f"firncore {firncore.__version__}; boundary {boundary:.1f} m from the eye; {samples} samples")
    print(f"bands: " + ", ".join(f"{s.firn.voxel_size * 100:.0f} cm {'surface' if s in bands and s not in volumes else 'volume'}"
                                  for s in bands))
    print("distance from the boundary   volume side   surface side   surface / volume")
    for width in (0.1, 0.2, 0.3):
        near = luminance[(distance >= boundary * (1 - width)) & (distance < boundary)]
        far = luminance[(distance >= boundary) & (distance < boundary * (1 + width))]
        print(f"within {width * 100:.0f} %:{'':17}{near.mean():.4f} ({near.size} px)   {far.mean():.4f} ({far.size} px)"
              f"   {far.mean() / near.mean():.4f}")


main()
