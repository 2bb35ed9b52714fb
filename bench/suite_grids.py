"""The suite cases' baked grids kept in a folder (bench/bake_suite.py's inputs, no reference and no render), with
`--car` the car's too (bench/car_scene.py's inputs, FINAL), and two such folders compared case by case with
bench/grids_identical.py: a change meant to keep behaviour checked on every case at once.

    PYTHONPATH=build/python /usr/bin/python3 bench/suite_grids.py bake FOLDER [--cases a,b] [--quality Q] [--seed S]
                                                                      [--car CAR_INPUTS]
    /usr/bin/python3 bench/suite_grids.py compare BEFORE AFTER      # exit status 0 when every case is identical
"""

import argparse
import os
import shutil
import sys

import grids_identical


def bake(folder, names, quality, seed, car=""):
    import bake_suite as S

    os.makedirs(folder, exist_ok=True)
    if car:
        import car_bake

        car = car_bake.car_folder(car)
        path = shutil.copy(os.path.join(car, "car_density.vdb"), os.path.join(folder, "car.vdb"))
        stats = car_bake.bake_copy(path, *car_bake.car_inputs(car), seed)
        print(f"car: baked ({stats['voxels']} active voxels)", flush=True)
    for case in S.cases():
        if names and case.name not in names:
            continue
        path = os.path.join(folder, case.name + ".vdb")
        S.write_density(path, case.density, case.voxel)
        stats = S.firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                                quality=quality, seed=seed, sky_samples=0)
        print(f"{case.name}: baked ({stats['traced_voxels']} traced voxels)", flush=True)


def compare(before, after):
    names = sorted(name for name in os.listdir(before) if name.endswith(".vdb"))
    different = []
    for name in names:
        print(f"== {name[:-4]}")
        if not grids_identical.compare(os.path.join(before, name), os.path.join(after, name)):
            different.append(name[:-4])
    print(f"{len(names)} cases, " + (f"DIFFERENT: {', '.join(different)}" if different else "ALL IDENTICAL"))
    return not different


def main():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="what", required=True)
    baking = sub.add_parser("bake", help="bake the cases into FOLDER/NAME.vdb")
    baking.add_argument("folder")
    baking.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    baking.add_argument("--quality", default="FINAL")
    baking.add_argument("--seed", type=int, default=0)
    baking.add_argument("--car", default="", help="also the car, from bench/car_scene.py's folder (FINAL)")
    comparing = sub.add_parser("compare", help="compare BEFORE's cases with AFTER's")
    comparing.add_argument("before")
    comparing.add_argument("after")
    args = parser.parse_args()
    if args.what == "bake":
        bake(args.folder, [n for n in args.cases.split(",") if n], args.quality, args.seed, args.car)
        return 0
    return 0 if compare(args.before, args.after) else 1


if __name__ == "__main__":
    sys.exit(main())
