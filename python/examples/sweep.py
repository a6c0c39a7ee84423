"""A parameter sweep as one would run it in a notebook: every exact shadow stage's frame time
against the image size on the Cornell box, plotted with matplotlib.

    pip install ./python matplotlib
    python python/examples/sweep.py [--out sweep.png]
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import umbra  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--scene", default=str(ROOT / "scenes" / "cornell.toml"))
parser.add_argument("--out", default="sweep.png")
args = parser.parse_args()

scene = umbra.load(args.scene)
stages = ["bouknight-kelley", "atherton-weiler-greenberg", "crow", "nishita-nakamae"]
widths = [160, 320, 640, 1280]
times = {s: [] for s in stages}
for w in widths:
    sized = scene.with_size(w, w * 3 // 4)
    for row in umbra.bench(sized, shadows=stages, runs=3, warmup=1):
        times[row["shadows"]].append(row["median_ms"])
        print(f"{w:5} px wide  {row['shadows']:28} {row['median_ms']:8.2f} ms")

pixels = [w * (w * 3 // 4) / 1e6 for w in widths]
fig, ax = plt.subplots(figsize=(6, 4))
for s in stages:
    ax.plot(pixels, times[s], marker="o", label=s)
ax.set_xlabel("megapixels")
ax.set_ylabel("frame, median ms")
ax.set_title(f"{pathlib.Path(args.scene).name}: exact shadow stages against image size")
ax.legend()
fig.tight_layout()
fig.savefig(args.out, dpi=120)
print(f"wrote {args.out}")
