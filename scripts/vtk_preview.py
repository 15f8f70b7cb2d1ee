#!/usr/bin/python3
"""Preview one frame of a gapflow ParaView series without ParaView: the files are read with
VTK's own XML reader (python3-vtk9) and drawn with matplotlib (top view, spheres coloured by
|velocity|, board z ignored; in 3D the marker also ignores height).

Usage: scripts/vtk_preview.py DIR/run.pvd FRAME OUT.png   (FRAME: index in the collection)"""
import os
import sys
import xml.etree.ElementTree as ET

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.collections import PatchCollection
from matplotlib.patches import Circle, Polygon
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader


def read(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


pvd, frame, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
sets = ET.parse(pvd).getroot().findall("./Collection/DataSet")
files = {s.get("part"): os.path.join(os.path.dirname(pvd), s.get("file"))
         for s in sets if s.get("timestep") == sorted({x.get("timestep") for x in sets}, key=float)[frame]}
t = float([s.get("timestep") for s in sets if s.get("part") == "0"][frame])
particles, boundary = read(files["0"]), read(files["1"])

fig, ax = plt.subplots(figsize=(3.4, 10))
pts = vtk_to_numpy(boundary.GetPoints().GetData()) * 1e3
offsets = vtk_to_numpy(boundary.GetPolys().GetOffsetsArray())
part = vtk_to_numpy(boundary.GetCellData().GetArray("part"))
for k in range(len(offsets) - 1):
    ax.add_patch(Polygon(pts[offsets[k]:offsets[k + 1], :2], closed=True,
                         color="#3c3e46" if part[k] < 2 else "#8c5a32"))
xyz = vtk_to_numpy(particles.GetPoints().GetData()) * 1e3
radius = vtk_to_numpy(particles.GetPointData().GetArray("radius_m")) * 1e3
speed = vtk_to_numpy(particles.GetPointData().GetArray("speed_m_s"))
discs = PatchCollection([Circle((x, y), r) for (x, y, _), r in zip(xyz, radius)], cmap="viridis")
discs.set_array(speed)
discs.set_clim(0, 0.5)
ax.add_collection(discs)
fig.colorbar(discs, ax=ax, fraction=0.08, label="speed (m/s)")
ax.set_xlim(pts[:, 0].min(), pts[:, 0].max())
ax.set_ylim(-60, pts[:, 1].max())
ax.set_aspect("equal")
ax.set_xlabel("x (mm)")
ax.set_ylabel("y (mm, uphill)")
ax.set_title(f"{os.path.basename(files['0'])}\nread by VTK, t = {t:.2f} s, {particles.GetNumberOfPoints()} spheres",
             fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=100, bbox_inches="tight")
