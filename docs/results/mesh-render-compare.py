#!/usr/bin/env python3
"""Checks that two builds of `hapto render` give the same god-object results on meshes.

Makes mesh scenes (spheres of 10^3, 5x10^4 and 10^6 triangles, a torus, a terrain) and the
default cube scene, paths that touch, press, slide over facet edges and vertices and wander,
renders each with both binaries under three indexes, and prints per run the largest proxy
(m) and force (N) difference and how many ticks' contact counts differ. Used for issue 15 (the
mesh tick): every run printed 0 m, 0 N, 0 (bit for bit the same).

    python3 docs/results/mesh-render-compare.py OLD/hapto NEW/hapto --work /tmp/mesh-compare
"""
import argparse
import csv
import math
import os
import random
import subprocess
import sys


def norm(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def write_path(name, points):
    with open(name, "w") as f:
        f.write("x,y,z\n")
        for p in points:
            f.write("%.17g,%.17g,%.17g\n" % tuple(p))


def sphere_path(radius, step, press, n, wave):
    """Down onto the pole, a wavy slide at a varying depth under the surface, back out."""
    points = []
    r = radius + 0.005
    while r > radius - press:
        points.append((0.0, 0.0, r))
        r -= step
    a, b, da = 0.0, 0.0, step / (radius - press)
    for i in range(n):
        d = norm((math.sin(a), wave * math.sin(2 * a) + math.sin(b), math.cos(a)))
        depth = radius - press + press * 0.8 * math.sin(i * 0.013)
        points.append(tuple(depth * c for c in d))
        a += da * (1 + 0.5 * math.sin(i * 0.07))
        b += 0.3 * da * math.cos(i * 0.011)
        if abs(a) > 0.6:
            da = -da
    last = points[-1]
    length = math.sqrt(sum(c * c for c in last))
    points += [tuple(c / length * (length + k * step) for c in last) for k in range(40)]
    return points


def walk(lo, hi, step, n, seed):
    """A smooth random walk kept inside the box lo..hi."""
    rng = random.Random(seed)
    p = [rng.uniform(a, b) for a, b in zip(lo, hi)]
    v = [rng.gauss(0, 1) for _ in range(3)]
    points = []
    for _ in range(n):
        v = [0.9 * c + 0.45 * rng.gauss(0, 1) for c in v]
        d = norm(v)
        p = [min(max(c + step * e, a), b) for c, e, a, b in zip(p, d, lo, hi)]
        points.append(tuple(p))
    return points


def compare(old_csv, new_csv):
    with open(old_csv) as f:
        old = list(csv.reader(f))[1:]
    with open(new_csv) as f:
        new = list(csv.reader(f))[1:]
    if len(old) != len(new):
        return None
    dp = df = 0.0
    contacts = differ = 0
    for a, b in zip(old, new):
        x = [float(v) for v in a[1:10]]
        y = [float(v) for v in b[1:10]]
        dp = max(dp, max(abs(p - q) for p, q in zip(x[3:6], y[3:6])))
        df = max(df, max(abs(p - q) for p, q in zip(x[6:9], y[6:9])))
        differ += a[10] != b[10]
        contacts += a[10] != "0"
    return len(old), contacts, dp, df, differ


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--work", default="mesh-compare")
    args = ap.parse_args()
    args.old, args.new = os.path.abspath(args.old), os.path.abspath(args.new)
    os.makedirs(args.work, exist_ok=True)
    os.chdir(args.work)
    run = lambda *cmd: subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    hapto = args.old
    for name, shape, n in [("s1k", "sphere", 1000), ("s50k", "sphere", 50000),
                           ("s1m", "sphere", 1000000), ("torus", "torus", 20000),
                           ("terrain", "terrain", 50000)]:
        if not os.path.exists(name + ".json"):
            run(hapto, "scene", "mesh", "--shape", shape, "--triangles", str(n), "-o", name + ".json")
    if not os.path.exists("cube.json"):
        run(hapto, "scene", "default", "-o", "cube.json")
    radius = 0.05  # the generated sphere's default 0.1 m diameter
    write_path("sphere-slide.csv", sphere_path(radius, 0.0005, 0.001, 6000, 0.3))
    write_path("sphere-slow.csv", sphere_path(radius, 0.00005, 0.0004, 6000, 0.5))
    write_path("sphere-deep.csv", sphere_path(radius, 0.001, 0.004, 4000, 0.8))
    write_path("sphere-walk.csv", walk((-0.015, -0.015, 0.04), (0.015, 0.015, 0.0525), 0.0004, 8000, 4))
    write_path("torus-walk.csv", walk((0.02, -0.04, -0.03), (0.077, 0.04, 0.03), 0.0004, 12000, 5))
    write_path("terrain-walk.csv", walk((-0.05, -0.035, -0.05), (0.05, 0.04, 0.05), 0.0005, 12000, 6))
    write_path("cube-walk.csv", walk((-0.12,) * 3, (0.12,) * 3, 0.001, 20000, 7))
    write_path("cube-walk2.csv", walk((-0.12,) * 3, (0.12,) * 3, 0.003, 20000, 8))
    runs = [(s, p) for s in ("s1k", "s50k", "s1m")
            for p in ("sphere-slide", "sphere-slow", "sphere-deep", "sphere-walk")]
    runs += [("torus", "torus-walk"), ("terrain", "terrain-walk"), ("cube", "cube-walk"),
             ("cube", "cube-walk2")]
    same = True
    for scene, path in runs:
        for index in ("octree:2:0.005", "octree:8:0.0005", "grid:64"):
            outs = []
            for tag, binary in (("old", args.old), ("new", args.new)):
                out = "%s-%s-%s-%s.csv" % (scene, path, index.replace(":", "_"), tag)
                run(binary, "render", "--scene", scene + ".json", "--path",
                    path + ".csv", "--index", index, "-o", out)
                outs.append(out)
            r = compare(*outs)
            if r is None:
                print("%-10s %-14s %-16s tick counts differ" % (scene, path, index))
                same = False
                continue
            ticks, contacts, dp, df, differ = r
            same = same and dp == 0 and df == 0 and differ == 0
            print("%-10s %-14s %-16s ticks %6d in contact %6d  max |d proxy| %.3g m  "
                  "max |d force| %.3g N  contact counts differ %d"
                  % (scene, path, index, ticks, contacts, dp, df, differ))
    print("bit for bit the same" if same else "DIFFERENT")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
