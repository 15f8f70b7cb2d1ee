#!/usr/bin/env python3
"""Overlap of touching discs in a 2D run's ParaView frames (issue 15: why J grows with the step).

Usage: scripts/overlap_2d.py VTK_DIR [--frames 2:8] [--label TEXT]

Reads particles_*.vtp (gapflow run --vtk DIR: positions and radii, ASCII) and, over the chosen
frames, every pair closer than 1.02 (r_i + r_j): the share that overlap, and the overlap
(r_i + r_j - distance) / (r_i + r_j) of the overlapping ones: mean and maximum. Prints one markdown
table row. O(N^2) per frame: meant for a few hundred discs.
"""
import argparse
import glob
import math
import re


def array(text, name):
    m = re.search(r'Name="%s"[^>]*>(.*?)</DataArray>' % name, text, re.S)
    return [float(x) for x in m.group(1).split()]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("vtk_dir")
    ap.add_argument("--frames", default="2:8", help="python slice of the sorted frames (default 2:8: flowing)")
    ap.add_argument("--label", default="")
    a = ap.parse_args()
    lo, hi = (int(x) for x in a.frames.split(":"))
    near = overlapping = 0
    total = biggest = 0.0
    for f in sorted(glob.glob(a.vtk_dir + "/particles_*.vtp"))[lo:hi]:
        text = open(f).read()
        p, r = array(text, "position_m"), array(text, "radius_m")
        xy = [(p[3 * i], p[3 * i + 1]) for i in range(len(r))]
        for i in range(len(r)):
            for j in range(i + 1, len(r)):
                s = r[i] + r[j]
                d = math.hypot(xy[i][0] - xy[j][0], xy[i][1] - xy[j][1])
                if d < 1.02 * s:
                    near += 1
                    if d < s:
                        overlapping += 1
                        total += (s - d) / s
                        biggest = max(biggest, (s - d) / s)
    mean = total / overlapping if overlapping else 0.0
    print(f"| {a.label or a.vtk_dir} | {near} | {100 * overlapping / max(1, near):.0f} % | {100 * mean:.3f} % "
          f"| {100 * biggest:.2f} % |")


if __name__ == "__main__":
    main()
