#!/usr/bin/env python3
"""A picture of one snapshot of `knotsweep run --vtk DIR`, drawn as ParaView draws it (the same VTK readers and
filters), with VTK's offscreen renderer: the centre line as a tube of the rod's radius coloured by curvature, the
loaded contacts as beads (blue: sticking, orange: slipping). Needs `pip install vtk` (the wheel renders through EGL
or OSMesa without a display; otherwise run it under `xvfb-run`).

    knotsweep run --n 3 --protocol adaptive --out n3.json --vtk vtk
    python3 tools/paraview_screenshot.py vtk/n3.pvd --label before_inversion --out docs/paraview-knot.png
"""
import argparse
import os
import re

import vtk


def snapshots(pvd):
    """(label, l_k bar, centre line file, contacts file) of each snapshot of a knotsweep .pvd, in time order."""
    text = open(pvd).read()
    entries = re.findall(r'<!-- (\w+): l_k bar ([\d.]+).*?-->\s*<DataSet[^>]*file="([^"]+)"/>\s*'
                         r'<DataSet[^>]*file="([^"]+)"/>', text)
    base = os.path.dirname(pvd)
    return [(label, float(l), os.path.join(base, a), os.path.join(base, b)) for label, l, a, b in entries]


def read(path):
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def knot_actors(line, contacts):
    """The tube coloured by curvature, its colour bar, and the contact beads."""
    radius = line.GetPointData().GetArray("radius").GetValue(0)
    tube = vtk.vtkTubeFilter()
    tube.SetInputData(line)
    tube.SetRadius(radius)
    tube.SetNumberOfSides(32)
    tube.CappingOn()
    lut = vtk.vtkColorTransferFunction()
    top = line.GetPointData().GetArray("curvature").GetRange()[1]
    for x, rgb in [(0.0, (0.27, 0.0, 0.33)), (0.25, (0.23, 0.32, 0.55)), (0.5, (0.13, 0.57, 0.55)),
                   (0.75, (0.37, 0.79, 0.38)), (1.0, (0.99, 0.91, 0.14))]:
        lut.AddRGBPoint(x * top, *rgb)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(tube.GetOutputPort())
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("curvature")
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(0.0, top)
    tube_actor = vtk.vtkActor()
    tube_actor.SetMapper(mapper)
    tube_actor.GetProperty().SetSpecular(0.3)
    tube_actor.GetProperty().SetOpacity(0.55)  # the beads sit where the tubes touch
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("curvature (1/m)")
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.0f")
    bar.SetWidth(0.08)
    bar.SetHeight(0.6)
    bar.SetPosition(0.9, 0.2)
    bar.UnconstrainedFontSizeOn()
    for t in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        t.SetFontSize(16)
        t.SetColor(0.1, 0.1, 0.1)
        t.ShadowOff()
        t.ItalicOff()
    bead = vtk.vtkSphereSource()
    bead.SetRadius(0.6 * radius)
    bead.SetThetaResolution(16)
    bead.SetPhiResolution(16)
    glyphs = vtk.vtkGlyph3D()
    glyphs.SetInputData(contacts)
    glyphs.SetSourceConnection(bead.GetOutputPort())
    glyphs.SetScaleModeToDataScalingOff()
    glyphs.SetColorModeToColorByScalar()
    contacts.GetPointData().SetActiveScalars("stick")
    stick = vtk.vtkLookupTable()
    stick.SetNumberOfTableValues(2)
    stick.SetTableValue(0, 0.95, 0.45, 0.1, 1.0)
    stick.SetTableValue(1, 0.1, 0.4, 0.95, 1.0)
    stick.SetTableRange(0, 1)
    bead_mapper = vtk.vtkPolyDataMapper()
    bead_mapper.SetInputConnection(glyphs.GetOutputPort())
    bead_mapper.SetLookupTable(stick)
    bead_mapper.SetScalarRange(0, 1)
    bead_actor = vtk.vtkActor()
    bead_actor.SetMapper(bead_mapper)
    return tube_actor, bar, bead_actor


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("pvd")
    ap.add_argument("--label", default="before_inversion", help="the first snapshot with this label (else the last)")
    ap.add_argument("--out", default="paraview-knot.png")
    ap.add_argument("--size", default="1200x700")
    args = ap.parse_args()
    found = snapshots(args.pvd)
    label, l_k_bar, line_file, contacts_file = next((f for f in found if f[0] == args.label), found[-1])
    line, contacts = read(line_file), read(contacts_file)
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1, 1, 1)
    renderer.SetUseDepthPeeling(1)
    for actor in knot_actors(line, contacts):
        renderer.AddActor(actor)
    note = vtk.vtkTextActor()
    sticking = sum(contacts.GetPointData().GetArray("stick").GetValue(i) for i in range(contacts.GetNumberOfPoints()))
    note.SetInput(f"{os.path.basename(args.pvd)}: {label}, l_k bar {l_k_bar:.1f}; "
                  f"{contacts.GetNumberOfPoints()} loaded contacts ({sticking} sticking: blue; slipping: orange)")
    note.GetTextProperty().SetFontSize(20)
    note.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    note.SetPosition(12, 12)
    renderer.AddActor(note)
    # Frame the knot: the loaded contacts' box; the camera looks across the pull axis, from a little below.
    box = contacts.GetBounds() if contacts.GetNumberOfPoints() else line.GetBounds()
    centre = [(box[2 * i] + box[2 * i + 1]) / 2 for i in range(3)]
    extent = max(box[2 * i + 1] - box[2 * i] for i in range(3))
    camera = renderer.GetActiveCamera()
    camera.SetFocalPoint(*centre)
    camera.SetPosition(centre[0], centre[1] - 0.8 * extent, centre[2] + 2.2 * extent)
    camera.SetViewUp(0, 1, 0)
    camera.SetViewAngle(30)
    renderer.ResetCameraClippingRange()
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(*map(int, args.size.split("x")))
    window.SetMultiSamples(0)  # depth peeling needs no multisampling
    window.SetAlphaBitPlanes(1)
    window.AddRenderer(renderer)
    window.Render()
    image = vtk.vtkWindowToImageFilter()
    image.SetInput(window)
    image.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(args.out)
    writer.SetInputConnection(image.GetOutputPort())
    writer.Write()
    print(f"{args.out}: {label} at l_k bar {l_k_bar:.2f}")


if __name__ == "__main__":
    main()
