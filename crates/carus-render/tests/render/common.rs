//! Test meshes and helpers shared by the rendering tests.

use carus_render::{Image, Renderer};

/// Opens the headless renderer or fails with the reason (and the packages to install).
pub fn renderer() -> Renderer {
    Renderer::new_headless()
        .unwrap_or_else(|e| panic!("carus-render tests need a GPU or lavapipe: {e}"))
}

/// A box between `min` and `max` with flat faces (four vertices per face),
/// counter-clockwise seen from outside.
pub fn cuboid(min: [f32; 3], max: [f32; 3]) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let corner = |i: usize| {
        [
            if i & 1 == 0 { min[0] } else { max[0] },
            if i & 2 == 0 { min[1] } else { max[1] },
            if i & 4 == 0 { min[2] } else { max[2] },
        ]
    };
    // Corner indices of each face, counter-clockwise from outside, and its normal.
    let faces: [([usize; 4], [f32; 3]); 6] = [
        ([0, 4, 6, 2], [-1.0, 0.0, 0.0]),
        ([1, 3, 7, 5], [1.0, 0.0, 0.0]),
        ([0, 1, 5, 4], [0.0, -1.0, 0.0]),
        ([2, 6, 7, 3], [0.0, 1.0, 0.0]),
        ([0, 2, 3, 1], [0.0, 0.0, -1.0]),
        ([4, 5, 7, 6], [0.0, 0.0, 1.0]),
    ];
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for (corners, normal) in faces {
        let base = positions.len() as u32;
        positions.extend(corners.map(corner));
        normals.extend([normal; 4]);
        indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    (positions, normals, indices)
}

/// Columns and rows spanned by pixels that differ from `background`.
pub fn silhouette(image: &Image, background: [u8; 4]) -> Option<([u32; 2], [u32; 2])> {
    let mut span: Option<([u32; 2], [u32; 2])> = None;
    for y in 0..image.height() {
        for x in 0..image.width() {
            if image.pixel(x, y) != Some(background) {
                let ([x0, x1], [y0, y1]) = span.unwrap_or(([x, x], [y, y]));
                span = Some(([x0.min(x), x1.max(x)], [y0.min(y), y1.max(y)]));
            }
        }
    }
    span
}

/// Largest per-channel difference of two pixels.
pub fn channel_distance(a: [u8; 4], b: [u8; 4]) -> u8 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(y))
        .max()
        .unwrap_or(0)
}
