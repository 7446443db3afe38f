"""Map the synthetic demo from Python and look at what the map renders.

Every frame's depth and segmentation go into one `sndt.Map` per trajectory as numpy
arrays; then each map is rendered into its frames and scored with the paper's metrics
(`sndt.evaluate`, the command line's evaluation). The picture shows, for one frame, the
network's labels, the map rendered from the frame's pose, and the ground truth.

    pip install ./python matplotlib
    python examples/python/map_synthetic.py                 # writes out/python/view.png
    python examples/python/map_synthetic.py --labels gt --show

No display is needed: the picture is written to a file (`--show` also opens a window).
"""

import argparse
import pathlib
import time

import numpy as np

import sndt


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--dataset", default="synthetic:2:100", help="anything `sndt map` reads")
    p.add_argument("--every", type=int, default=5, help="map every n-th frame (default 5)")
    p.add_argument("--cell", type=float, default=0.1, help="voxel edge, metres")
    p.add_argument("--labels", choices=["pred", "gt"], default="pred",
                   help="the network's top-1 labels (default) or the ground truth")
    p.add_argument("--out", default="out/python", help="where view.png goes")
    p.add_argument("--show", action="store_true", help="also show the picture in a window")
    args = p.parse_args()

    import matplotlib

    if not args.show:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pairs = []
    for trajectory in sndt.open_dataset(args.dataset, every=args.every):
        m = sndt.Map(cell=args.cell)
        frames = list(trajectory)
        seconds = 0.0
        for f in frames:
            if args.labels == "pred":
                if f.topk is None:
                    raise SystemExit(f"{args.dataset} has no predicted labels: use --labels gt")
                labels = f.topk[0][0]  # the network's best class per pixel, (H, W)
            else:
                labels = f.labels
            t = time.perf_counter()
            m.integrate(f.depth, labels, intrinsics=f.intrinsics, pose=f.pose,
                        depth_kind=f.depth_kind)
            seconds += time.perf_counter() - t
        print(f"{trajectory.name}: {len(frames)} frames, {len(m)} voxels, "
              f"{1e3 * seconds / max(len(frames), 1):.1f} ms/frame")
        pairs.append((m, frames))

    metrics = sndt.evaluate(pairs)
    print(f"{args.labels} labels at {args.cell * 100:.0f} cm: mIoU {100 * metrics.miou:.2f} %, "
          f"invR {100 * metrics.invr:.2f} %, mPAcc {100 * metrics.mpacc:.2f} % "
          f"over {metrics.frames} frames")

    # One frame: what the network said, what the map renders there, the ground truth.
    m, frames = pairs[0]
    f = frames[len(frames) // 2]
    h, w = f.shape
    view, depth = m.render(f.pose, f.intrinsics, w, h)
    colors = np.array(sndt.CLASS_COLORS, dtype=np.uint8)
    panels = [("ground truth", f.labels), ("map rendered at this pose", view)]
    if f.topk is not None:
        panels.insert(0, ("network (top-1)", f.topk[0][0]))
    fig, axes = plt.subplots(1, len(panels) + 1, figsize=(5 * (len(panels) + 1), 4))
    for ax, (title, labels) in zip(axes, panels):
        ax.imshow(colors[labels])
        ax.set_title(title)
    shown = axes[-1].imshow(np.where(depth > 0, depth, np.nan), cmap="viridis")
    axes[-1].set_title("rendered depth (m)")
    fig.colorbar(shown, ax=axes[-1], fraction=0.035)
    for ax in axes:
        ax.axis("off")
    fig.suptitle(f"{f.id}: mIoU {100 * metrics.miou:.1f} % over {metrics.frames} frames")
    fig.tight_layout()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig.savefig(out / "view.png", dpi=80)
    print(f"wrote {out / 'view.png'}")
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
