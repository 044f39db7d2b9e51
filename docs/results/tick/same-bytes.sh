#!/bin/bash
# Do two hapto binaries give the same answers? same-bytes.sh OLD_HAPTO NEW_HAPTO [WORKDIR]
# Generates (once, in WORKDIR, default ./same-bytes) a 10^6- and a 20 480-triangle sphere
# (10 cm), 20 000 random 2 mm cubes in a 5 cm work cube, and three device paths: great-circle
# arcs 0.5-2 mm inside the sphere at 0.5 mm a tick, arcs 0.5-3 mm inside at 1.5 mm a tick (each
# 6 000 ticks, after 10 ticks coming in from 5 mm outside), and a seeded walk through the cubes
# at up to 1 mm a tick (12 000 ticks). Then runs `hapto render` with both binaries over each
# scene and path under several indexes and compares the outputs byte for byte (cmp): every
# tick's proxy, force and contact count. Prints "same" or "DIFFERENT" per case; exits 1 if any
# case differs. Used for the changes in tick-motions.md that must not change a result.
set -eu
old=$1 new=$2 dir=${3:-same-bytes}
mkdir -p "$dir" && cd "$dir"
[ -f s6.json ] || "$old" scene mesh --triangles 1000000 -o s6.json > /dev/null
[ -f s4.json ] || "$old" scene mesh --triangles 20000 -o s4.json > /dev/null
[ -f cubes.json ] || "$old" scene random --count 20000 --size 0.002 --workspace 0.05 \
  -o cubes.json > /dev/null
{ [ -f p_slow.csv ] && [ -f p_fast.csv ] && [ -f p_cubes.csv ]; } || python3 - <<'PY'
import math, random
random.seed(7)
def sphere_path(name, n, step, depth_lo, depth_hi, radius=0.05):
    pts = []
    while len(pts) < n:  # great circles through random pairs of orthonormal directions
        a = [random.gauss(0, 1) for _ in range(3)]
        la = math.sqrt(sum(x * x for x in a)); a = [x / la for x in a]
        b = [random.gauss(0, 1) for _ in range(3)]
        d = sum(x * y for x, y in zip(a, b)); b = [y - d * x for x, y in zip(a, b)]
        lb = math.sqrt(sum(x * x for x in b)); b = [x / lb for x in b]
        length = random.uniform(0.05, 0.2)
        r = radius - random.uniform(depth_lo, depth_hi)
        for i in range(int(length / step)):
            t = i * step / radius
            pts.append([r * (math.cos(t) * a[k] + math.sin(t) * b[k]) for k in range(3)])
    with open(name, "w") as f:
        f.write("x,y,z\n")
        p = pts[0]
        s = (radius + 0.005) / math.sqrt(sum(x * x for x in p))
        for j in range(10):  # come in from 5 mm outside
            f.write(",".join("%.9g" % (x * (s - (s - 1) * j / 10)) for x in p) + "\n")
        for p in pts[:n]:
            f.write(",".join("%.9g" % x for x in p) + "\n")
sphere_path("p_slow.csv", 6000, 0.0005, 0.0005, 0.002)
sphere_path("p_fast.csv", 6000, 0.0015, 0.0005, 0.003)
with open("p_cubes.csv", "w") as f:
    f.write("x,y,z\n")
    p = [0.0, 0.0, 0.0]; v = [0.0, 0.0, 0.0]
    for i in range(12000):
        v = [0.9 * x + random.gauss(0, 0.0003) for x in v]
        speed = math.sqrt(sum(x * x for x in v))
        if speed > 0.001:
            v = [x * 0.001 / speed for x in v]
        p = [max(-0.02, min(0.02, x + y)) for x, y in zip(p, v)]
        f.write(",".join("%.9g" % x for x in p) + "\n")
PY
status=0
check() { # scene path index
  local ix=()
  [ "$3" = default ] || ix=(--index "$3")
  "$old" render --scene "$1.json" --path "$2.csv" "${ix[@]}" -o old.csv
  "$new" render --scene "$1.json" --path "$2.csv" "${ix[@]}" -o new.csv
  if cmp -s old.csv new.csv; then echo "same      $1 $2 $3"; else echo "DIFFERENT $1 $2 $3"; status=1; fi
}
for s in s6 s4; do for p in p_slow p_fast; do check $s $p default; done; done
check s6 p_fast grid:64
check s6 p_fast octree:4:0.0002
for ix in default octree:8:0.001 octree:1:0.0005 grid:32 grid:100 brute; do check cubes p_cubes $ix; done
exit $status
