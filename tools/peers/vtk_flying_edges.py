#!/usr/bin/python3
"""Peer for the bench row terrain.mesh.256: VTK's vtkFlyingEdges3D on a field file.

    vtk_flying_edges.py PREFIX.json THREADS RUNS

Reads PREFIX.json + PREFIX.raw (the terrain's field file: little-endian float32, x fastest),
contours the zero level with normals (as terrain_mesh_build makes them) on THREADS threads,
RUNS times, and prints one JSON line: {"ms":[...],"triangles":T,"threads":N,"backend":B}.
Only the filter's update is timed, not the reading. Exits 1 when VTK is not installed
(Debian: python3-vtk9); the bench then leaves the peer rows out.
"""
import json
import sys
import time

try:
    import vtk
except ImportError:
    sys.exit(1)


def main():
    prefix_json, threads, runs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    with open(prefix_json) as f:
        header = json.load(f)
    nx, ny, nz = header["dims"]
    reader = vtk.vtkImageReader2()
    reader.SetFileName(prefix_json[: -len(".json")] + ".raw")
    reader.SetDataScalarTypeToFloat()
    reader.SetDataByteOrderToLittleEndian()
    reader.SetFileDimensionality(3)
    reader.SetDataExtent(0, nx - 1, 0, ny - 1, 0, nz - 1)
    reader.SetDataSpacing(header["spacing"], header["spacing"], header["spacing"])
    reader.Update()
    smp = vtk.vtkSMPTools()
    smp.Initialize(threads)
    times = []
    triangles = 0
    for _ in range(runs):
        fe = vtk.vtkFlyingEdges3D()
        fe.SetInputData(reader.GetOutput())
        fe.SetValue(0, 0.0)
        fe.ComputeNormalsOn()
        fe.ComputeGradientsOff()
        fe.ComputeScalarsOff()
        start = time.perf_counter()
        fe.Update()
        times.append((time.perf_counter() - start) * 1000.0)
        triangles = fe.GetOutput().GetNumberOfPolys()
    print(json.dumps({"ms": times, "triangles": triangles, "threads": smp.GetEstimatedNumberOfThreads(),
                      "backend": smp.GetBackend()}))


main()
