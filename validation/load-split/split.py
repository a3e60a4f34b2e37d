"""Where a dragged pad's force goes: the medium's internal forces on the pad, by term and by
where the cell lies in the undeformed mesh (THEORY.md, "Where the ratio goes").

Needs a tmc built with split.patch applied (see README.md); prints one row per drag.
usage: python3 split.py TMC_BINARY [n] [mu] [l] [a] [beta2]
"""
import os
import subprocess
import sys
import tempfile

tmc = sys.argv[1]
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
with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "pad.toml")
    open(path, "w").write(case)
    # the pad spans a <= X <= a + 2 in the undeformed mesh: "under" it, "ahead", "behind"
    env = dict(os.environ, TMC_DIAG=f"solid,{a},{a + 2.0}")
    p = subprocess.run([tmc, "solve", path, "-o", os.path.join(d, "out"), "-q"],
                       env=env, capture_output=True, text=True)
lines = [ln.split() for ln in p.stderr.splitlines() if ln.startswith("DIAG")]
print(f"n = {n}, l = {l}, a = {a}, mu = {mu}, beta2 = {beta2}: {'completed' if p.returncode == 0 else 'stopped'}")
print("drag  Ft/Fn   fric/law(under)  Fn under: law reg  Fn ahead  Fn")
marks = [0.25, 0.5, 1.0, 1.5, 2.0]
for w in lines:
    t = float(w[2])
    v = {w[i]: (float(w[i + 1]), float(w[i + 2])) for i in range(3, len(w), 3)}
    if t <= 1.0:
        continue
    drag = 2.0 * (t - 1.0)
    if not marks or drag < marks[0] - 1e-9:
        continue
    while marks and drag >= marks[0] - 1e-9:
        marks.pop(0)
    parts = [k + z for k in ("med", "fric", "inert") for z in "123"]
    fx = sum(v[k][0] for k in parts)
    fy = sum(v[k][1] for k in parts)
    law_u, reg_u = v["noreg1"][1], v["med1"][1] - v["noreg1"][1]
    ahead = v["med2"][1]
    print(f"{drag:4.2f}  {-fx / fy:.4f}  {-v['fric1'][0] / law_u:.4f}           "
          f"{law_u:5.2f} {reg_u:5.2f}    {ahead:5.2f}     {fy:5.2f}")
