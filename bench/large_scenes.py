"""The scale table of issue 16: the car sample, a street and the valley sample, each snowed, baked and rendered at
500 × 280 (16 samples). Per scene: the area the snow lies on, its active voxels (every band), and per stage (Add
Snow Layer, Bake Scattering, render) the wall time and the peak resident memory of this Blender process (sampled
every 20 ms; the bake's world probe runs in a child Blender, not counted), with Cycles' own peak ("Peak" of its
status line: the dense volume textures included).

bench/run.sh bench/large_scenes.py -- [car] [street] [valley]
"""

import os
import resource
import sys
import tempfile
import threading
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow as car  # noqa: E402
import sample_common as common  # noqa: E402
import valley  # noqa: E402

WIDTH, SAMPLES = 500, 16


class PeakMemory:
    """Peak resident memory (MB) of this process over a stage, from /proc/self/status."""

    def __init__(self):
        self.peak, self._stop = 0.0, threading.Event()

    @staticmethod
    def resident_mb():
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
        return 0.0

    def _watch(self):
        while not self._stop.wait(0.02):
            self.peak = max(self.peak, self.resident_mb())

    def __enter__(self):
        self.peak = self.resident_mb()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *_exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self.resident_mb())


def cpu_seconds():
    """Processor time of this process and its finished children (the world probe), s: what the stage would take
    alone on one core, whatever else the machine runs."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


class Stage:
    """Wall time (s), processor time (s) and peak resident memory (MB) of one stage."""

    def __init__(self, fn, *args, **kwargs):
        with PeakMemory() as memory:
            started, cpu = time.perf_counter(), cpu_seconds()
            self.result = fn(*args, **kwargs)
            self.seconds, self.cpu = time.perf_counter() - started, cpu_seconds() - cpu
        self.peak_gb = memory.peak / 1024.0

    def cell(self):
        return f"{self.seconds:.0f} s ({self.cpu:.0f} s CPU), {self.peak_gb:.2f} GB"


def street_scene():
    """A street of 120 m: houses as boxes on both sides, parked cars as boxes, a camera at eye height."""
    scene = common.new_scene()
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    ground = bpy.context.object
    ground.scale = (40.0, 130.0, 1.0)
    bpy.ops.object.transform_apply(scale=True)
    targets = [ground]
    for i in range(12):
        for side in (-1, 1):
            bpy.ops.mesh.primitive_cube_add(size=1.0, location=(side * 13.0, -55.0 + i * 10.0, 4.0),
                                            scale=(8.0, 8.5, 8.0))
            targets.append(bpy.context.object)
    for i in range(8):
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=((-1) ** i * 5.5, -45.0 + i * 12.0, 0.75),
                                        scale=(1.8, 4.2, 1.4))
        targets.append(bpy.context.object)
    common.nishita_sky(scene, sun_elevation_deg=25.0, sun_rotation_deg=200.0)
    common.sun(elevation_deg=25.0, rotation_deg=200.0, irradiance=4.0)
    common.camera(location=(1.5, -62.0, 1.7), look_at=(0.0, 0.0, 2.0), lens=35.0)
    return scene, targets


def snowed_area(objects):
    """m² of faces facing up (the targets' area that can hold snow), world space."""
    area = 0.0
    for obj in objects:
        matrix = obj.matrix_world
        for polygon in obj.data.polygons:
            normal = (matrix.to_3x3() @ polygon.normal)
            if normal.z > 0.0:
                area += polygon.area * abs(matrix.to_3x3().determinant()) ** (2 / 3)
    return area


SCENES = {
    "car": (car.build_scene, dict(depth=0.12, spacing=0.06, voxel_size=0.02, level_of_detail="OFF")),
    "street": (street_scene, dict(depth=0.1, spacing=0.05, level_of_detail="AUTO")),
    "valley": (valley.build_scene, valley.SNOW),
}


def dense_mb(snows):
    """MB Cycles copies densely for the volume bands: 4 bytes per box voxel of density and 16 per box voxel of the
    four RGB source grids, 2x coarser (docs/bake.md, Memory)."""
    from firn.common.core import firncore

    total = 0.0
    for snow in snows:
        box = firncore.grid_statistics(bpy.path.abspath(snow.data.filepath), "density")["box_voxels"]
        total += box[0] * box[1] * box[2] * (4 + 4 * 16 / 8) / 1e6
    return total


def run(name, folder):
    from firn.common.core import firncore

    build, settings = SCENES[name]
    scene, targets = build()
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, WIDTH * 14 // 25
    area = snowed_area(targets)
    add = Stage(common.add_snow_bands, targets, **settings)
    bands = add.result
    voxels = sum(firncore.grid_statistics(bpy.path.abspath(s.data.filepath), "density")["active_voxels"]
                 for s in bands)
    volumes = valley.volume_bands(bands)
    bake = Stage(common.bake, volumes)
    render = Stage(common.render_peak_mb, scene, os.path.join(folder, f"{name}.png"), WIDTH, SAMPLES, (25, 14))
    print(f"| {name} | {area:,.0f} | {len(bands)} ({len(volumes)} volumes) | {voxels / 1e6:.1f} M | {add.cell()} | "
          f"{bake.cell()} | {render.cell()}; Cycles {render.result / 1024:.2f} GB, dense grids "
          f"{dense_mb(volumes) / 1024:.2f} GB | {add.seconds + bake.seconds + render.seconds:.0f} s "
          f"({add.cpu + bake.cpu + render.cpu:.0f} s CPU) |", flush=True)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    names = argv or list(SCENES)
    folder = tempfile.mkdtemp(prefix="firn_bench_")
    load = os.getloadavg()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} cores, load average "
          f"{load[0]:.1f} at the start; {WIDTH} × 280 px, {SAMPLES} samples")
    print("| scene | target area m² | snow objects | active voxels | add snow: time, peak RSS | bake: time, peak RSS "
          "| render: time, peak RSS | end to end |")
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        run(name, folder)


main()
