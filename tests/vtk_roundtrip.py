#!/usr/bin/env python3
"""Read the ParaView series written by tests/test_view.cpp (VtkSeries.ReadBackByVtk)
back with VTK's own XML readers (python3-vtk9) and check counts and values.
Usage: vtk_roundtrip.py DIR   (exit 0 when every check holds)."""
import os
import sys
import xml.etree.ElementTree as ET

from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
from vtkmodules.util.numpy_support import vtk_to_numpy


def read(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode():
        raise SystemExit(f"{path}: VTK reader error {r.GetErrorCode()}")
    return r.GetOutput()


def check(cond, what):
    if not cond:
        raise SystemExit("FAILED: " + what)


d = sys.argv[1]
sets = ET.parse(os.path.join(d, "run.pvd")).getroot().findall("./Collection/DataSet")
check(len(sets) == 4, f"run.pvd lists {len(sets)} data sets, not 4 (2 frames x particles, boundary)")
check([float(s.get("timestep")) for s in sets] == [0.0, 0.0, 0.5, 0.5], "timesteps 0, 0.5")
for s in sets:
    pd = read(os.path.join(d, s.get("file")))
    if s.get("part") == "0":
        check(pd.GetNumberOfPoints() == 3 and pd.GetNumberOfVerts() == 3, "3 particles as vertices")
        x = pd.GetPoint(1)
        check(abs(x[0] - 0.01) < 1e-12 and abs(x[1] - 0.2) < 1e-12 and abs(x[2] - 0.004) < 1e-12, f"position {x}")
        p = pd.GetPointData()
        check(abs(vtk_to_numpy(p.GetArray("radius_m"))[0] - 0.0039) < 1e-12, "radius")
        v = vtk_to_numpy(p.GetArray("velocity_m_s"))
        check(v.shape == (3, 3) and abs(v[0][1] + 0.2) < 1e-12, f"velocity {v}")
        check(list(vtk_to_numpy(p.GetArray("id"))) == [7, 7, 9], "ids")
        check(list(vtk_to_numpy(p.GetArray("state"))) == [1, 1, 2], "states (arch, arch, passed)")
        w = vtk_to_numpy(p.GetArray("spin_rad_s"))
        check(list(w[2]) == [1.0, 2.0, 3.0], f"spin {w}")
    else:
        # 2 bottleneck walls, 2 retaining walls, top wall, the cylinder (48-gon)
        check(pd.GetNumberOfPolys() == 6, f"{pd.GetNumberOfPolys()} boundary polygons, not 6")
        part = list(vtk_to_numpy(pd.GetCellData().GetArray("part")))
        check(part == [0, 0, 1, 1, 1, 2], f"parts {part}")
        cyl = [pd.GetPoint(i) for i in range(pd.GetNumberOfPoints() - 48, pd.GetNumberOfPoints())]
        cx = sum(p[0] for p in cyl) / 48
        want = 0.001 if s.get("file").endswith("000001.vtp") else 0.0  # frame 1 shakes the obstruction 1 mm across
        check(abs(cx - want) < 1e-9, f"cylinder centre x {cx}, not {want}")
print("vtk round trip: ok")
