#!/usr/bin/python3
"""README.md's table: corner.py over loads, μ, corner radii and meshes (two at a time).

    /usr/bin/python3 table.py
"""
import subprocess
import sys
from multiprocessing import Pool
from pathlib import Path

HERE = Path(__file__).parent
RUNS = [(128, 64, delta, mu, r, 2.0) for r in (0.05, 0.1) for delta in (0.005, 0.01, 0.019)
        for mu in (0.1, 0.3, 0.5)]
RUNS += [(256, 128, 0.005, 0.3, 0.05, 2.0), (256, 128, 0.019, 0.3, 0.05, 2.0),
         (128, 64, 0.005, 1.0, 0.05, 2.0), (128, 64, 0.019, 0.3, 0.05, 3.0)]


def run(case):
    nx, ny, delta, mu, r, end = case
    out = subprocess.run([sys.executable, str(HERE / "corner.py"), str(nx), str(ny), str(delta),
                          str(mu), str(r), "--base-end", str(end)],
                         capture_output=True, text=True)
    rows = [[float(v) for v in line.split()] for line in out.stdout.splitlines()
            if line and line[0] != "#"]
    pressed = next(float(line.split()[-1]) for line in out.stdout.splitlines()
                   if line.startswith("# pressed"))
    head = f"| {nx} × {ny} | {end:g} | {r:g} | {delta:g} | {mu:g} | {pressed:.3f} |"
    if not rows or rows[-1][0] < 0.5 - 1e-9:
        reached = rows[-1][0] if rows else 0.0
        return head + f" stops at {reached:.3f} | | |"
    late = [row[3] for row in rows if row[0] >= 0.3 - 1e-9]
    back = max(row[4] for row in rows if row[0] >= 0.1 - 1e-9)
    spread = f"{(min(late) / mu - 1) * 100:+.1f} … {(max(late) / mu - 1) * 100:+.1f} %"
    return head + f" {spread.replace('-', '−')} | {rows[-1][2]:.3f} | {back:.3f} |"


if __name__ == "__main__":
    print("| mesh | base's end | corner radius | press δ | μ | F_n pressed | F_t/F_n from a drag "
          "of 0.3, against μ | F_n at the end | `back` from 0.1 |")
    print("|---|---|---|---|---|---|---|---|---|")
    with Pool(2) as pool:
        for line in pool.imap(run, RUNS):
            print(line, flush=True)
