"""Where a dragged body's force goes: the medium's internal forces on it, by term and by
where the cell lies in the undeformed mesh (docs/notes/2026-11-29-friction-measurements.md,
"Where the ratio goes" and "The one-cell block's leading end").

Needs a tmc built with split.patch applied (see README.md); prints one row per drag.
usage: python3 split.py TMC_BINARY [n] [mu] [l] [a] [beta2]      the pad of geo/pad.geo
       python3 split.py TMC_BINARY CASE.toml XB DRAG              a case whose body is "solid",
           held by the cells with undeformed x <= XB (zone 1) and beyond it (zone 2), dragged
           DRAG along x from t = 1 to 2 (the one-cell block of `make bench`: XB = 1.75, 0.5)
"""
import os
import subprocess
import sys
import tempfile


def diag(case_text, xa, xb):
    """Solve the case (its text) with the split on; the DIAG lines' forces per time, and
    whether the run completed."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "case.toml")
        open(path, "w").write(case_text)
        env = dict(os.environ, TMC_DIAG=f"solid,{xa},{xb}")
        p = subprocess.run([tmc, "solve", path, "-o", os.path.join(d, "out"), "-q"],
                           env=env, capture_output=True, text=True)
    rows = []
    for ln in p.stderr.splitlines():
        if ln.startswith("DIAG"):
            w = ln.split()
            rows.append((float(w[2]),
                         {w[i]: (float(w[i + 1]), float(w[i + 2])) for i in range(3, len(w), 3)}))
    return rows, p.returncode == 0


def at_drags(rows, drag_of, marks):
    """The rows at the first steps reaching each of the drags `marks`, with their drag."""
    out = []
    for t, v in rows:
        if t <= 1.0:
            continue
        drag = drag_of(t)
        if not marks or drag < marks[0] - 1e-9:
            continue
        while marks and drag >= marks[0] - 1e-9:
            marks.pop(0)
        out.append((drag, v))
    return out


def totals(v):
    """The body's whole tangential and normal force (x, y) over every term and zone."""
    parts = [k + z for k in ("med", "fric", "inert") for z in "123"]
    return sum(v[k][0] for k in parts), sum(v[k][1] for k in parts)


tmc = sys.argv[1]
if len(sys.argv) > 2 and sys.argv[2].endswith(".toml"):
    xb, drag_total = float(sys.argv[3]), float(sys.argv[4])
    rows, done = diag(open(sys.argv[2]).read(), 0.0, xb)
    print(f"{sys.argv[2]}, zone 2 beyond x = {xb}: {'completed' if done else 'stopped'}")
    print("tangential forces positive against the drag")
    print("drag  Ft/Fn   Fn    | zone 1: law's normal, friction | zone 2: law's normal, friction, law's shear, reg.'s shear")
    marks = [0.6 * drag_total, 0.8 * drag_total, drag_total]
    for drag, v in at_drags(rows, lambda t: drag_total * (t - 1.0), marks):
        fx, fy = totals(v)
        law1, law2 = v["noreg1"], v["noreg2"]
        reg2 = v["med2"][0] - law2[0]
        print(f"{drag:4.2f}  {-fx / fy:.4f} {fy:6.3f} | {law1[1]:6.3f} {-v['fric1'][0]:6.3f} "
              f"| {law2[1]:6.3f} {-v['fric2'][0]:6.3f} {-law2[0]:+6.3f} {-reg2:+6.3f}")
    sys.exit(0)
n = int(sys.argv[2]) if len(sys.argv) > 2 else 16
mu = float(sys.argv[3]) if len(sys.argv) > 3 else 0.3
l = int(sys.argv[4]) if len(sys.argv) > 4 else 1
a = float(sys.argv[5]) if len(sys.argv) > 5 else 3.0
beta2 = sys.argv[6] if len(sys.argv) > 6 else "1e-2"
geo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "geo", "pad.geo")
case = f"""mesh = "{os.path.abspath(geo)}"
[mesh_options]
params = {{ n = {n}, m = {n // 2}, l = {l}, a = {a} }}
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
rho = 1e-4
[[region]]
group = "medium"
kind = "medium"
gamma = 1e-4
beta2 = {beta2}
friction = {{ mu = {mu}, normal = [0, 1] }}
rho = 1e-4
[[bc]]
group = "bottom"
ux = 0.0
uy = 0.0
[[bc]]
group = "top"
uy = -0.3
path = [0.0, 1.0, 1.0]
[[bc]]
group = "top"
ux = 2.0
path = [0.0, 0.0, 1.0]
[steps]
initial = 0.025
max = 0.025
path = [0.0, 1.0, 1.0]
"""
# the pad spans a <= X <= a + 2 in the undeformed mesh: "under" it, "ahead", "behind"
rows, done = diag(case, a, a + 2.0)
print(f"n = {n}, l = {l}, a = {a}, mu = {mu}, beta2 = {beta2}: {'completed' if done else 'stopped'}")
print("drag  Ft/Fn   fric/law(under)  Fn under: law reg  Fn ahead  Fn")
for drag, v in at_drags(rows, lambda t: 2.0 * (t - 1.0), [0.25, 0.5, 1.0, 1.5, 2.0]):
    fx, fy = totals(v)
    law_u, reg_u = v["noreg1"][1], v["med1"][1] - v["noreg1"][1]
    ahead = v["med2"][1]
    print(f"{drag:4.2f}  {-fx / fy:.4f}  {-v['fric1'][0] / law_u:.4f}           "
          f"{law_u:5.2f} {reg_u:5.2f}    {ahead:5.2f}     {fy:5.2f}")
