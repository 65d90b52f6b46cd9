import gmsh, sys
def build(hexes):
    gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("box")
    gmsh.model.occ.addBox(0, 0, 0, 20, 10, 5)
    gmsh.model.occ.synchronize()
    surfs = gmsh.model.getEntities(2)
    bottom = [s[1] for s in surfs if abs(gmsh.model.occ.getCenterOfMass(2, s[1])[2]) < 1e-9]
    top = [s[1] for s in surfs if abs(gmsh.model.occ.getCenterOfMass(2, s[1])[2] - 5) < 1e-9]
    gmsh.model.addPhysicalGroup(3, [1], name="tissue")
    gmsh.model.addPhysicalGroup(2, bottom, name="bottom")
    gmsh.model.addPhysicalGroup(2, top, name="top")
    if hexes:
        for c in gmsh.model.getEntities(1):
            gmsh.model.mesh.setTransfiniteCurve(c[1], 3)
        for s in surfs:
            gmsh.model.mesh.setTransfiniteSurface(s[1]); gmsh.model.mesh.setRecombine(2, s[1])
        gmsh.model.mesh.setTransfiniteVolume(1)
    else:
        gmsh.option.setNumber("Mesh.MeshSizeMin", 5.0); gmsh.option.setNumber("Mesh.MeshSizeMax", 5.0)
    gmsh.model.mesh.generate(3)
for hexes, stem in [(False, "box_tet"), (True, "box_hex")]:
    build(hexes)
    for v, suffix in [(2.2, "v22"), (4.1, "v41"), (4.0, "v40")]:
        gmsh.option.setNumber("Mesh.MshFileVersion", v)
        gmsh.write(f"{stem}_{suffix}.msh")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.write(f"{stem}_bin.msh")
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(f"{stem}_gmsh.inp")
    gmsh.write(f"{stem}_gmsh.vtk")
    gmsh.finalize()
