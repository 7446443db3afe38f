"""The map update driven from Python, against the same update in Rust and against
pyoctomap's `OcTree.insertPointCloud` on the same frames (scripts/bench-python.sh).

Frames: the first FRAMES frames of the synthetic living room (1024x768, ground-truth
labels), read once into memory. Each method maps them into a fresh map at CELL metres, one
thread, after a warm-up pass into a throwaway map; only the update call is inside the clock.
Printed: ms/frame (mean and median of the timed frames), per run and over RUNS runs
alternating the methods.

- sndt from Python: `Map.integrate(depth, labels, intrinsics=..., pose=...)`, the
  argument checks included; against `Map.integrate_frame(frame)`, the same update on the
  frame Rust already holds (the command line's path), alternating in one process.
- pyoctomap: `OcTree(CELL).insertPointCloud(points, origin, max_range=20, lazy_eval=False,
  discretize=True)`, as scripts/peers/octomap_bench.cpp calls OctoMap's C++. Its world
  points are computed before the clock from the same depth (the points sndt integrates).
"""

import argparse
import statistics
import time

import numpy as np

import sndt


def world_points(f):
    """The frame's measured pixels as world points (float64, C order) and the camera origin."""
    fx, fy, cx, cy = f.intrinsics
    h, w = f.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    z = f.depth
    ok = np.isfinite(z) & (z > 0)
    cam = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], axis=-1)[ok].astype(np.float64)
    pose = f.pose
    world = cam @ pose[:3, :3].T + pose[:3, 3]
    return np.ascontiguousarray(world), np.ascontiguousarray(pose[:3, 3])


def time_sndt(arrays, cell):
    warm = sndt.Map(cell=cell)
    for depth, labels, k, pose in arrays[:2]:
        warm.integrate(depth, labels, intrinsics=k, pose=pose)
    m = sndt.Map(cell=cell)
    out = []
    for depth, labels, k, pose in arrays:
        t = time.perf_counter()
        m.integrate(depth, labels, intrinsics=k, pose=pose)
        out.append(1e3 * (time.perf_counter() - t))
    return out


def time_sndt_rust(frames, cell):
    """The same update through `Map.integrate_frame`: the frame is already Rust's, so this
    is the command line's update plus one call from Python, no arrays to check."""
    warm = sndt.Map(cell=cell)
    for f in frames[:2]:
        warm.integrate_frame(f)
    m = sndt.Map(cell=cell)
    out = []
    for f in frames:
        t = time.perf_counter()
        m.integrate_frame(f)
        out.append(1e3 * (time.perf_counter() - t))
    return out


def paired_overhead(arrays, frames, cell):
    """Per frame, the arrays path into one map and the Rust-frame path into another, in
    alternating order: the ratio of the two times for each frame (drift of the machine's
    speed cancels out of each pair)."""
    a, b = sndt.Map(cell=cell), sndt.Map(cell=cell)
    ratios = []
    for i, ((depth, labels, k, pose), f) in enumerate(zip(arrays, frames)):
        def arrays_path():
            t = time.perf_counter()
            a.integrate(depth, labels, intrinsics=k, pose=pose)
            return time.perf_counter() - t

        def frame_path():
            t = time.perf_counter()
            b.integrate_frame(f)
            return time.perf_counter() - t

        if i % 2:
            ta, tb = arrays_path(), frame_path()
        else:
            tb, ta = frame_path(), arrays_path()
        ratios.append(ta / tb)
    assert a.snapshot() == b.snapshot()
    return ratios


def time_pyoctomap(clouds, cell):
    import pyoctomap

    warm = pyoctomap.OcTree(cell)
    for pts, origin in clouds[:2]:
        warm.insertPointCloud(pts, origin, max_range=20.0, lazy_eval=False, discretize=True)
    tree = pyoctomap.OcTree(cell)
    out = []
    for pts, origin in clouds:
        t = time.perf_counter()
        tree.insertPointCloud(pts, origin, max_range=20.0, lazy_eval=False, discretize=True)
        out.append(1e3 * (time.perf_counter() - t))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--frames", type=int, default=12)
    p.add_argument("--cell", type=float, default=0.1)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--no-octomap", action="store_true")
    args = p.parse_args()
    (traj,) = sndt.open_dataset(f"synthetic:1:{args.frames}").trajectories
    frames = list(traj)
    # Every input is made before the clocks run (a Frame's arrays are copied out of Rust on
    # each attribute access).
    arrays = [(f.depth, f.labels, f.intrinsics, f.pose) for f in frames]
    clouds = [world_points(f) for f in frames]
    print(f"{len(frames)} frames of {frames[0].shape[1]}x{frames[0].shape[0]}, "
          f"{statistics.mean(len(c[0]) for c in clouds):,.0f} points each, cell {args.cell} m")
    runs = {"sndt: Map.integrate(arrays)": [], "sndt: Map.integrate_frame (Rust's frame)": [],
            "pyoctomap": []}
    for r in range(args.runs):
        runs["sndt: Map.integrate(arrays)"].append(time_sndt(arrays, args.cell))
        runs["sndt: Map.integrate_frame (Rust's frame)"].append(time_sndt_rust(frames, args.cell))
        if not args.no_octomap:
            runs["pyoctomap"].append(time_pyoctomap(clouds, args.cell))
    ratios = [r for _ in range(args.runs) for r in paired_overhead(arrays, frames, args.cell)]
    print(f"Map.integrate(arrays) / Map.integrate_frame, per frame, alternating: median "
          f"{statistics.median(ratios):.3f} (quartiles {statistics.quantiles(ratios, n=4)[0]:.3f}"
          f"-{statistics.quantiles(ratios, n=4)[2]:.3f}, {len(ratios)} frames)")
    for name, per_run in runs.items():
        if not per_run:
            continue
        means = [statistics.mean(x) for x in per_run]
        medians = [statistics.median(x) for x in per_run]
        print(f"{name}: mean {statistics.median(means):.2f} ms/frame "
              f"(runs: {', '.join(f'{x:.2f}' for x in means)}), "
              f"median {statistics.median(medians):.2f}")


if __name__ == "__main__":
    main()
