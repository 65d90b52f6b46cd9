//! A geodesic sphere (subdivided icosahedron): the parameter domain of the
//! star-shaped fetal surfaces.

use std::collections::HashMap;

use glam::DVec3;

/// Unit vertices and outward counter-clockwise triangles of an icosahedron
/// subdivided `levels` times (10 * 4^levels + 2 vertices).
pub(crate) fn geodesic_sphere(levels: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push((vertices[a as usize] + vertices[b as usize]).normalize());
                (vertices.len() - 1) as u32
            })
        };
        let mut finer = Vec::with_capacity(triangles.len() * 4);
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            finer.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = finer;
    }
    (vertices, triangles)
}

/// Moves the vertex nearest to each unit direction onto it, so that
/// landmarks become surface vertices. Returns the vertex index of each
/// direction, or `None` when two directions claim the same vertex (the
/// sphere is too coarse for them).
pub(crate) fn pin_directions(vertices: &mut [DVec3], directions: &[DVec3]) -> Option<Vec<u32>> {
    let mut pinned: Vec<u32> = Vec::with_capacity(directions.len());
    for &d in directions {
        let nearest = (0..vertices.len()).max_by(|&a, &b| vertices[a].dot(d).total_cmp(&vertices[b].dot(d)))?;
        if pinned.contains(&(nearest as u32)) {
            return None;
        }
        vertices[nearest] = d;
        pinned.push(nearest as u32);
    }
    Some(pinned)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::TriSurface;

    #[test]
    fn the_sphere_is_closed_and_outward() {
        for levels in 0..4 {
            let (v, t) = geodesic_sphere(levels);
            assert_eq!(v.len(), 10 * 4usize.pow(levels) + 2);
            TriSurface::new(v, t).check_closed().unwrap();
        }
    }
}
