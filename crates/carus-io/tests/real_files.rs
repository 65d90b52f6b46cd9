//! The readers on files written by Gmsh 4.15 and meshio 5.3 (see
//! tests/data/real/README.md): every format gives the same mesh.

use std::path::{Path, PathBuf};

use carus_fem::{ElementKind, Mesh};
use carus_io::{read_mesh, LengthUnit, MeshFile};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(name)
}

fn read(name: &str) -> MeshFile {
    read_mesh(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Total volume of a tetrahedral mesh (positive when every element is).
fn tet_volume(mesh: &Mesh) -> f64 {
    mesh.elements()
        .map(|e| {
            let p = |i: usize| mesh.nodes[e[i] as usize];
            let d = |i: usize| [p(i)[0] - p(0)[0], p(i)[1] - p(0)[1], p(i)[2] - p(0)[2]];
            let (a, b, c) = (d(1), d(2), d(3));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Sorted coordinates, to compare meshes whose node order differs.
fn sorted_nodes(mesh: &Mesh) -> Vec<[i64; 3]> {
    let mut nodes: Vec<[i64; 3]> = mesh
        .nodes
        .iter()
        .map(|p| p.map(|x| (x * 1e6).round() as i64))
        .collect();
    nodes.sort_unstable();
    nodes
}

fn outward_z(mesh: &Mesh, surface: &str) -> Vec<f64> {
    mesh.surfaces[surface]
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|n| mesh.nodes[n as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        })
        .collect()
}

#[test]
fn gmsh_versions_agree_on_the_tetrahedral_box() {
    let v41 = read("box_tet_v41.msh");
    for other in ["box_tet_v22.msh", "box_tet_v40.msh"] {
        assert_eq!(read(other).mesh, v41.mesh, "{other}");
    }
    let mesh = &v41.mesh;
    assert_eq!(mesh.kind, ElementKind::T4);
    assert_eq!(mesh.element_sets["tissue"].len(), mesh.element_count());
    assert!(
        (tet_volume(mesh) - 20.0 * 10.0 * 5.0).abs() < 1e-9,
        "every tetrahedron positive"
    );
    // Surfaces face out of the box; their names also give node sets.
    assert!(outward_z(mesh, "bottom").iter().all(|&nz| nz < 0.0));
    assert!(outward_z(mesh, "top").iter().all(|&nz| nz > 0.0));
    assert!(mesh.node_sets["bottom"]
        .iter()
        .all(|&n| mesh.nodes[n as usize][2] == 0.0));
    let metres = v41.clone().to_metres(LengthUnit::Millimetre);
    assert!((tet_volume(&metres.mesh) - 1e-6).abs() < 1e-18);
}

#[test]
fn gmsh_versions_agree_on_the_hexahedral_box() {
    let v41 = read("box_hex_v41.msh");
    for other in ["box_hex_v22.msh", "box_hex_v40.msh"] {
        assert_eq!(read(other).mesh, v41.mesh, "{other}");
    }
    assert_eq!(v41.mesh.kind, ElementKind::H8);
    assert_eq!((v41.mesh.element_count(), v41.mesh.node_count()), (8, 27));
    assert_eq!(
        v41.mesh.surfaces["top"].len(),
        8,
        "4 quadrangles, 2 triangles each"
    );
}

#[test]
fn binary_gmsh_is_refused_with_the_fix() {
    for name in ["box_tet_bin.msh", "box_hex_bin.msh"] {
        let err = read_mesh(&data(name)).unwrap_err().to_string();
        assert!(err.contains("binary") && err.contains("-bin 0"), "{err}");
    }
}

#[test]
fn gmsh_abaqus_and_vtk_exports_give_the_same_mesh() {
    for stem in ["box_tet", "box_hex"] {
        let reference = read(&format!("{stem}_v41.msh")).mesh;
        let inp = read(&format!("{stem}_gmsh.inp")).mesh;
        assert_eq!(inp.kind, reference.kind);
        assert_eq!(sorted_nodes(&inp), sorted_nodes(&reference), "{stem}.inp");
        assert_eq!(inp.element_count(), reference.element_count());
        // Gmsh exports the physical surfaces as CPS3 element sets.
        assert_eq!(inp.surfaces["top"].len(), reference.surfaces["top"].len());
        assert_eq!(inp.element_sets["tissue"].len(), reference.element_count());
        let vtk = read(&format!("{stem}_gmsh.vtk")).mesh;
        assert_eq!(sorted_nodes(&vtk), sorted_nodes(&reference), "{stem}.vtk");
        assert_eq!(vtk.element_count(), reference.element_count());
    }
}

#[test]
fn meshio_conversions_give_the_same_mesh_and_sets() {
    let reference = read("box_tet_v41.msh").mesh;
    for name in [
        "box_tet_meshio.vtu",
        "box_tet_meshio_ascii.vtu",
        "box_tet_meshio.vtk",
        "box_tet_meshio.inp",
        "box_tet_vtk_raw.vtu",
        "box_tet_vtk_raw_zlib.vtu",
        "box_tet_vtk_raw_lz4.vtu",
        "box_tet_vtk_base64_zlib.vtu",
        "box_tet_vtk9_ascii.vtk",
        "box_tet_vtk9_binary.vtk",
    ] {
        let mesh = read(name).mesh;
        // meshio's ascii VTU keeps 11 significant digits.
        assert_eq!(mesh.nodes.len(), reference.nodes.len(), "{name}");
        for (a, b) in mesh.nodes.iter().zip(&reference.nodes) {
            assert!(
                (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9),
                "{name}: {a:?} vs {b:?}"
            );
        }
        assert_eq!(mesh.connectivity, reference.connectivity, "{name}");
    }
    // meshio keeps Gmsh's physical tags as the cell array `gmsh:physical`,
    // and VTK's writers keep it, as ParaView would when saving.
    for name in [
        "box_tet_meshio.vtu",
        "box_tet_vtk_raw_zlib.vtu",
        "box_tet_vtk9_binary.vtk",
    ] {
        let vtu = read(name).mesh;
        let physical: Vec<&String> = vtu
            .element_sets
            .keys()
            .filter(|k| k.starts_with("gmsh:physical_"))
            .collect();
        assert_eq!(physical.len(), 1, "{name}");
        assert_eq!(
            vtu.element_sets[physical[0]].len(),
            reference.element_count(),
            "{name}"
        );
        let surfaces = vtu
            .surfaces
            .keys()
            .filter(|k| k.starts_with("gmsh:physical_"))
            .count();
        assert_eq!(surfaces, 2, "{name}: bottom and top");
    }
}
