//! A pelvis-like test scene drawn from the standard views and written as
//! PNG files under the target's tmp folder, to be looked at by eye.

use carus_render::{Camera, ColourMap, ContactSheet, RenderMesh, Scene, View, LABEL_STRIP};

use crate::common::renderer;

/// A ring around the z axis, like a pelvic inlet.
fn torus(major: f32, minor: f32, rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut positions = Vec::new();
    for i in 0..rings {
        let u = std::f32::consts::TAU * i as f32 / rings as f32;
        for j in 0..segments {
            let v = std::f32::consts::TAU * j as f32 / segments as f32;
            let r = major + minor * v.cos();
            positions.push([r * u.cos(), r * u.sin(), minor * v.sin()]);
        }
    }
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let at = |a: u32, b: u32| (a % rings) * segments + b % segments;
            indices.extend([
                at(i, j),
                at(i + 1, j),
                at(i + 1, j + 1),
                at(i, j),
                at(i + 1, j + 1),
                at(i, j + 1),
            ]);
        }
    }
    (positions, indices)
}

/// A sagging open disc (a pelvic floor sheet) with a radial scalar field.
fn floor(radius: f32, sag: f32, rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>, Vec<f32>) {
    let mut positions = vec![[0.0, 0.0, -sag]];
    let mut scalars = vec![1.0];
    for i in 1..=rings {
        let s = i as f32 / rings as f32;
        for j in 0..segments {
            let a = std::f32::consts::TAU * j as f32 / segments as f32;
            positions.push([
                radius * s * a.cos(),
                radius * s * a.sin(),
                -sag * (1.0 - s * s),
            ]);
            scalars.push(1.0 - s * s);
        }
    }
    let ring_start = |i: u32| 1 + (i - 1) * segments;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.extend([0, ring_start(1) + j, ring_start(1) + (j + 1) % segments]);
    }
    for i in 1..rings {
        for j in 0..segments {
            let (a, b) = (ring_start(i), ring_start(i + 1));
            let k = (j + 1) % segments;
            indices.extend([a + j, b + j, b + k, a + j, b + k, a + k]);
        }
    }
    (positions, indices, scalars)
}

#[test]
fn sample_scene_from_the_standard_views() {
    let mut renderer = renderer();
    let (ring, ring_indices) = torus(0.6, 0.16, 64, 24);
    let (sheet, sheet_indices, stretch) = floor(0.62, 0.3, 12, 48);
    let axis: Vec<[f32; 3]> = (0..=20)
        .map(|i| {
            let s = i as f32 / 20.0;
            [0.0, 0.4 * s * s, 0.9 - 1.6 * s]
        })
        .collect();
    let scene = Scene::new(vec![
        RenderMesh::new(
            "pelvis",
            ring.iter()
                .map(|p| [p[0], p[1] * 0.85, p[2] - 0.1])
                .collect(),
            ring_indices,
            [0.89, 0.85, 0.76],
        )
        .with_opacity(0.45),
        RenderMesh::sphere("fetal head", [0.05, 0.1, 0.35], 0.42, [0.93, 0.72, 0.62]),
        // A curved axis through the ring and two landmarks on it.
        RenderMesh::tube("pelvic axis", &axis, 0.025, [0.15, 0.35, 0.85]),
        RenderMesh::sphere("right landmark", [0.6, 0.0, -0.1], 0.05, [0.85, 0.1, 0.1]),
        RenderMesh::sphere("left landmark", [-0.6, 0.0, -0.1], 0.05, [0.1, 0.6, 0.1]),
        RenderMesh::new(
            "pelvic floor",
            sheet
                .iter()
                .map(|p| [p[0], p[1] * 0.85, p[2] - 0.25])
                .collect(),
            sheet_indices,
            [0.7; 3],
        )
        .with_scalars(stretch, [0.0, 1.0], ColourMap::Viridis),
    ]);
    let sheet = renderer
        .contact_sheet(
            &scene,
            &ContactSheet {
                views: vec![View::Anterior, View::Lateral, View::Inferior, View::Oblique],
                tile_size: [320, 320],
                ..ContactSheet::default()
            },
        )
        .unwrap();
    let superior = renderer
        .render(
            &scene,
            &Camera::standard(View::Superior, &scene.bounds().unwrap()),
            256,
            256,
        )
        .unwrap();
    let adapter = renderer.gpu().adapter_info();
    eprintln!(
        "sample drawn on {} ({:?}, {:?})",
        adapter.name, adapter.backend, adapter.device_type
    );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    sheet
        .save_png(dir.join("carus-render-sample-sheet.png"))
        .unwrap();
    superior
        .save_png(dir.join("carus-render-sample-superior.png"))
        .unwrap();

    // Seen from below, the floor's stretched centre (yellow end of viridis) faces the camera.
    let x = 8 + 2 * (320 + 8) + 160;
    let [r, g, b, _] = sheet.pixel(x, 8 + LABEL_STRIP + 160).unwrap();
    assert!(
        r > 120 && g > 120 && b < 110,
        "floor centre not yellow-green: {:?}",
        [r, g, b]
    );
    // From above, the head fills the middle of the inlet ring.
    let [r, g, b, _] = superior.pixel(128, 128).unwrap();
    assert!(
        r > g && g > b && r > 150,
        "head not seen through the inlet: {:?}",
        [r, g, b]
    );
}
