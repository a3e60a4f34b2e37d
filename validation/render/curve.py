#!/usr/bin/python3
"""Plot history.csv columns of a solved case against a column (default lambda), to PNG.

    /usr/bin/python3 validation/render/curve.py results/NAME out.png Q_top [--x lambda]
        [--scale-x 1.3333] [--xlabel ...] [--mark 0.25,0.5,1]
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("results")
    ap.add_argument("png")
    ap.add_argument("columns", nargs="+")
    ap.add_argument("--x", default="lambda")
    ap.add_argument("--scale-x", type=float, default=1.0)
    ap.add_argument("--xlabel")
    ap.add_argument("--mark", help="x values (before scaling) to mark with dots")
    a = ap.parse_args()
    with open(os.path.join(a.results, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    x = [float(r[a.x]) * a.scale_x for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for c in a.columns:
        if c not in rows[0]:
            raise SystemExit(f"history.csv has no column '{c}' (have {list(rows[0])})")
        y = [float(r[c]) for r in rows]
        ax.plot(x, y, ".-", label=c)
        if a.mark:
            marks = [float(v) * a.scale_x for v in a.mark.split(",")]
            pts = [(xi, yi) for xi, yi in zip(x, y) if any(abs(xi - m) < 1e-9 for m in marks)]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", ms=8, mfc="none", color="k")
    ax.set_xlabel(a.xlabel or a.x)
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(os.path.basename(os.path.normpath(a.results)))
    fig.tight_layout()
    fig.savefig(a.png, dpi=90)


if __name__ == "__main__":
    main()
