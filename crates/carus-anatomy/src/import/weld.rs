//! From triangles as stored to a clean surface: non-finite or absurdly
//! large coordinates refused with their triangle and vertex, duplicate vertices merged,
//! degenerate triangles dropped, flipped faces turned to agree with their
//! neighbours, and the surface's parts and openings counted.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::formats::RawMesh;
use super::ImportError;
use crate::surface::TriSurface;

/// What the importer found in a mesh and did to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshReport {
    /// Triangles in the file.
    pub triangles_read: usize,
    /// Distinct vertices after merging exact duplicates.
    pub vertices: usize,
    /// Triangles dropped because two of their corners coincide.
    pub degenerate_dropped: usize,
    /// Connected parts (triangles sharing vertices).
    pub parts: usize,
    /// Parts whose every edge borders exactly two triangles traversing it in
    /// opposite directions (closed, consistently oriented).
    pub closed_parts: usize,
    /// Edges bordering one triangle only (openings).
    pub open_edges: usize,
    /// Edges bordering more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges two triangles still run the same way after
    /// [`MeshReport::reoriented`]: a part that cannot be turned to agree (a
    /// surface with no outside, such as a Moebius band).
    #[serde(default)]
    pub unorientable_edges: usize,
    /// Triangles turned to run against their neighbours, as the rest of
    /// their part does (faces an exporter flipped).
    #[serde(default)]
    pub reoriented: usize,
    /// Whether a part facing into the bone (negative volume) was turned
    /// to face outwards ([`turn_parts_outwards`]).
    #[serde(default)]
    pub turned_outwards: bool,
}

/// The farthest a vertex may lie from the origin, in metres: a body fits
/// in metres and scanner coordinates stay within a few of them, so
/// anything beyond is a wrong unit or a broken export, and coordinates
/// near the float range would overflow areas and volumes downstream.
pub const MAX_COORDINATE_M: f64 = 1e3;

/// Checks coordinates, merges duplicate vertices (exactly equal after
/// scaling) and drops degenerate triangles; `scale` converts file units to
/// metres.
pub fn weld(path: &Path, raw: &RawMesh, scale: f64) -> Result<(TriSurface, MeshReport), ImportError> {
    let count = raw.positions.len();
    for (triangle, corners) in raw.triangles.iter().enumerate() {
        for (corner, &vertex) in corners.iter().enumerate() {
            let Some(p) = raw.positions.get(vertex as usize) else {
                return Err(ImportError::Format {
                    path: path.to_path_buf(),
                    format: "mesh",
                    message: format!(
                        "triangle {} of the file (counting from 1) refers to vertex index {vertex}, but there are {count} vertices",
                        triangle + 1
                    ),
                });
            };
            if !p.is_finite() {
                return Err(ImportError::NonFinite {
                    path: path.to_path_buf(),
                    triangle,
                    corner,
                    vertex: vertex as usize,
                });
            }
            let coordinate_m = p.abs().max_element() * scale;
            if coordinate_m > MAX_COORDINATE_M {
                return Err(ImportError::TooFar {
                    path: path.to_path_buf(),
                    triangle,
                    corner,
                    vertex: vertex as usize,
                    coordinate_m,
                });
            }
        }
    }
    if raw.triangles.is_empty() {
        return Err(ImportError::Empty {
            path: path.to_path_buf(),
            triangles_read: 0,
        });
    }

    // Merge by exact coordinate bits (+0.0 and -0.0 alike).
    let key = |p: DVec3| p.to_array().map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
    let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(count);
    let mut vertices = Vec::new();
    let mut remap = vec![0u32; count];
    for (i, &p) in raw.positions.iter().enumerate() {
        let scaled = p * scale;
        remap[i] = *index.entry(key(scaled)).or_insert_with(|| {
            vertices.push(scaled);
            (vertices.len() - 1) as u32
        });
    }
    let mut triangles = Vec::with_capacity(raw.triangles.len());
    let mut degenerate_dropped = 0;
    for t in &raw.triangles {
        let t = t.map(|v| remap[v as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            degenerate_dropped += 1;
        } else {
            triangles.push(t);
        }
    }
    if triangles.is_empty() {
        return Err(ImportError::Empty {
            path: path.to_path_buf(),
            triangles_read: raw.triangles.len(),
        });
    }
    let reoriented = orient_consistently(&mut triangles);
    // Keep only vertices some triangle uses.
    let mut used = vec![u32::MAX; vertices.len()];
    let mut kept = Vec::with_capacity(vertices.len());
    for t in &mut triangles {
        for v in t.iter_mut() {
            if used[*v as usize] == u32::MAX {
                used[*v as usize] = kept.len() as u32;
                kept.push(vertices[*v as usize]);
            }
            *v = used[*v as usize];
        }
    }
    let surface = TriSurface::new(kept, triangles);
    let report = MeshReport {
        reoriented,
        ..survey(&surface, raw.triangles.len(), degenerate_dropped)
    };
    Ok((surface, report))
}

/// Turns triangles that run against their neighbours so that every edge
/// shared by two triangles is crossed in opposite directions, the
/// winding a closed surface needs for an inside and an outside (an
/// exporter that flips a few faces otherwise leaves edges that look like
/// holes). Each connected part keeps the winding most of its triangles
/// had (on a tie, its first triangle's); in a part that cannot agree (a
/// surface with no outside) the edges where the turning met itself still
/// run the same way, and are counted by [`survey`]. Returns how many
/// triangles were turned.
fn orient_consistently(triangles: &mut [[u32; 3]]) -> usize {
    let edge = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut sharing: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(triangles.len() * 3 / 2);
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            sharing.entry(edge(t[k], t[(k + 1) % 3])).or_default().push(i as u32);
        }
    }
    let runs = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    // turn[i]: whether triangle i runs against the part's first triangle.
    let mut turn: Vec<Option<bool>> = vec![None; triangles.len()];
    let mut turned = 0;
    for seed in 0..triangles.len() {
        if turn[seed].is_some() {
            continue;
        }
        turn[seed] = Some(false);
        let (mut part, mut queue) = (vec![seed], vec![seed]);
        while let Some(i) = queue.pop() {
            let flipped = turn[i] == Some(true);
            let t = triangles[i];
            for k in 0..3 {
                // The edge as triangle i runs it once turned.
                let (a, b) = if flipped { (t[(k + 1) % 3], t[k]) } else { (t[k], t[(k + 1) % 3]) };
                let [p, q] = sharing[&edge(a, b)][..] else { continue };
                let n = if p as usize == i { q } else { p } as usize;
                if turn[n].is_none() {
                    // Agreeing, the neighbour runs the shared edge b to a.
                    turn[n] = Some(runs(&triangles[n], a, b));
                    part.push(n);
                    queue.push(n);
                }
            }
        }
        // Turn the minority: those against the seed, unless they are most.
        let against = part.iter().filter(|&&i| turn[i] == Some(true)).count();
        let seed_side_wins = 2 * against <= part.len();
        for &i in &part {
            if (turn[i] == Some(true)) == seed_side_wins {
                triangles[i].swap(1, 2);
                turned += 1;
            }
        }
    }
    turned
}

/// The connected part of each vertex (a representative vertex; triangles
/// sharing a vertex are one part).
pub(super) fn vertex_parts(surface: &TriSurface) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..surface.vertices.len() as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in &surface.triangles {
        let a = root(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = root(&mut parent, v);
            parent[b as usize] = a;
        }
    }
    (0..parent.len() as u32).map(|v| root(&mut parent, v)).collect()
}

/// How many triangles run each directed edge.
fn directed_uses(surface: &TriSurface) -> HashMap<(u32, u32), u32> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::with_capacity(surface.triangles.len() * 3);
    for t in &surface.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    directed
}

/// Counts parts, closed parts, open and non-manifold edges.
fn survey(surface: &TriSurface, triangles_read: usize, degenerate_dropped: usize) -> MeshReport {
    let part = vertex_parts(surface);
    let directed = directed_uses(surface);
    let mut part_of: HashMap<u32, bool> = surface.triangles.iter().map(|t| (part[t[0] as usize], true)).collect();
    let (mut open_edges, mut non_manifold_edges, mut unorientable_edges) = (0, 0, 0);
    for (&(a, b), &uses) in &directed {
        let back = directed.get(&(b, a)).copied().unwrap_or(0);
        let closed_here = uses == 1 && back == 1;
        if !closed_here {
            part_of.insert(part[a as usize], false);
        }
        // Count each undirected edge once.
        match (uses, back) {
            (1, 0) => open_edges += 1,
            (2, 0) => unorientable_edges += 1,
            (_, 0) => non_manifold_edges += 1,
            _ if a < b && uses + back > 2 => non_manifold_edges += 1,
            _ => {}
        }
    }
    MeshReport {
        triangles_read,
        vertices: surface.vertices.len(),
        degenerate_dropped,
        parts: part_of.len(),
        closed_parts: part_of.values().filter(|&&closed| closed).count(),
        open_edges,
        non_manifold_edges,
        unorientable_edges,
        reoriented: 0,
        turned_outwards: false,
    }
}

/// Turns each part of `surface` that faces into the volume it encloses
/// (its signed volume negative) to face outwards, and says how many: a
/// bone facing into itself would draw the fetus into it. Only a part whose
/// every edge some triangle crosses back has an inside for certain (bones
/// glued along shared edges count); one with an opening, or an edge no
/// turning made agree, is left as it faces.
pub fn turn_parts_outwards(surface: &mut TriSurface) -> usize {
    let part = vertex_parts(surface);
    let directed = directed_uses(surface);
    let mut enclosing: HashMap<u32, bool> = HashMap::new();
    let mut volume: HashMap<u32, f64> = HashMap::new();
    for (t, corners) in surface.triangles.iter().enumerate() {
        let p = part[corners[0] as usize];
        let sound = (0..3).all(|k| directed.contains_key(&(corners[(k + 1) % 3], corners[k])));
        *enclosing.entry(p).or_insert(true) &= sound;
        *volume.entry(p).or_default() += surface.volume_share(t);
    }
    let inward: Vec<u32> = volume.iter().filter(|&(p, &v)| v < 0.0 && enclosing[p]).map(|(&p, _)| p).collect();
    for t in surface.triangles.iter_mut() {
        if inward.contains(&part[t[0] as usize]) {
            t.swap(1, 2);
        }
    }
    inward.len()
}
