//! Boundary conditions compiled into the tables the GPU kernels read.
//!
//! Most nodes are free and unloaded, so the node kernel reads one word per
//! node (`NONE`) and only constrained or loaded nodes own a record:
//!
//! ```text
//! node_loads = [record offset per node | records]
//! record     = [kinds, shapes, ux, uy, uz, force_count, pressure_count,
//!               force_count x (shape, fx, fy, fz), pressure_count x slot]
//! ```
//! `kinds` holds 2 bits per component (0 free, 1 fixed, 2 imposed), `shapes`
//! 8 bits per component (the imposed displacement's load shape); f32 values
//! are stored as their bits. A pressure slot is the offset of one node's
//! share in the triangle force copies the pressure kernel writes. The order
//! of the CPU solver is kept: fixed, then imposed displacements (the last
//! one naming a component wins), then the coupling API (its own kernel).

use crate::loads::{BoundaryConditions, LoadShape};

use super::error::GpuError;

/// Record offset of a node with no condition and no load.
pub const NONE: u32 = u32::MAX;
/// Load-shape values per step that fit the per-step uniform record
/// (7 vec4 for t_n, 7 for t_n+1; shaders/common.wgsl `Step`).
pub const MAX_LOAD_SHAPES: usize = 28;

const FIXED: u32 = 1;
const IMPOSED: u32 = 2;

/// The boundary conditions of a run in GPU form.
#[derive(Debug, Clone, PartialEq)]
pub struct CompiledLoads {
    /// Distinct load shapes; the kernels index them.
    pub shapes: Vec<LoadShape>,
    pub node_loads: Vec<u32>,
    /// Per pressure triangle [n0, n1, n2, shape, pressure_pa as f32 bits].
    pub triangles: Vec<u32>,
    pub gravity_m_s2: [f64; 3],
}

#[derive(Default, Clone)]
struct NodeRecord {
    kinds: u32,
    shapes: u32,
    values: [f32; 3],
    forces: Vec<[u32; 4]>,
    pressure_slots: Vec<u32>,
}

impl CompiledLoads {
    /// Compiles `bc` for a mesh of `node_count` nodes whose triangle force
    /// copies start at `triangle_forces_at` in the force buffer. Refuses
    /// what the CPU solver refuses ([`BoundaryConditions::validate`]).
    pub fn new(
        bc: &BoundaryConditions,
        node_count: usize,
        triangle_forces_at: u32,
    ) -> Result<CompiledLoads, GpuError> {
        bc.validate(node_count)?;
        let mut shapes: Vec<LoadShape> = Vec::new();
        let mut shape_index = |shape: LoadShape| -> u32 {
            let i = match shapes.iter().position(|s| *s == shape) {
                Some(i) => i,
                None => {
                    shapes.push(shape);
                    shapes.len() - 1
                }
            };
            i as u32
        };
        let mut records: Vec<Option<NodeRecord>> = vec![None; node_count];
        for f in &bc.fixed {
            for &n in &f.nodes {
                let r = records[n as usize].get_or_insert_with(NodeRecord::default);
                for c in 0..3 {
                    if f.components[c] {
                        r.kinds = (r.kinds & !(3 << (2 * c))) | (FIXED << (2 * c));
                        r.values[c] = 0.0;
                    }
                }
            }
        }
        for d in &bc.displacements {
            let s = shape_index(d.shape);
            for &n in &d.nodes {
                let r = records[n as usize].get_or_insert_with(NodeRecord::default);
                for c in 0..3 {
                    if let Some(v) = d.components[c] {
                        r.kinds = (r.kinds & !(3 << (2 * c))) | (IMPOSED << (2 * c));
                        r.shapes = (r.shapes & !(0xff << (8 * c))) | (s << (8 * c));
                        r.values[c] = v as f32;
                    }
                }
            }
        }
        for f in &bc.forces {
            let s = shape_index(f.shape);
            for &n in &f.nodes {
                let r = records[n as usize].get_or_insert_with(NodeRecord::default);
                r.forces.push([
                    s,
                    (f.force_n[0] as f32).to_bits(),
                    (f.force_n[1] as f32).to_bits(),
                    (f.force_n[2] as f32).to_bits(),
                ]);
            }
        }
        let mut triangles = Vec::new();
        for p in &bc.pressures {
            let s = shape_index(p.shape);
            for tri in &p.triangles {
                let t = (triangles.len() / 5) as u32;
                for (a, &n) in tri.iter().enumerate() {
                    let r = records[n as usize].get_or_insert_with(NodeRecord::default);
                    r.pressure_slots
                        .push(triangle_forces_at + 9 * t + 3 * a as u32);
                }
                triangles.extend_from_slice(&[
                    tri[0],
                    tri[1],
                    tri[2],
                    s,
                    (p.pressure_pa as f32).to_bits(),
                ]);
            }
        }
        if shapes.len() > MAX_LOAD_SHAPES {
            return Err(GpuError::TooManyLoadShapes {
                count: shapes.len(),
                max: MAX_LOAD_SHAPES,
            });
        }
        let gravity_m_s2 = bc.gravity_m_s2.unwrap_or([0.0; 3]);
        let mut node_loads = vec![NONE; node_count];
        for (n, r) in records.iter().enumerate() {
            if let Some(r) = r {
                node_loads[n] = node_loads.len() as u32;
                let v = r.values.map(f32::to_bits);
                node_loads.extend_from_slice(&[
                    r.kinds,
                    r.shapes,
                    v[0],
                    v[1],
                    v[2],
                    r.forces.len() as u32,
                    r.pressure_slots.len() as u32,
                ]);
                node_loads.extend(r.forces.iter().flatten());
                node_loads.extend_from_slice(&r.pressure_slots);
            }
        }
        Ok(CompiledLoads {
            shapes,
            node_loads,
            triangles,
            gravity_m_s2,
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len() / 5
    }

    /// Values of every load shape at `t_s`, padded to the uniform record.
    pub fn shape_values(&self, t_s: f64) -> [f32; MAX_LOAD_SHAPES] {
        let mut out = [0.0; MAX_LOAD_SHAPES];
        for (o, s) in out.iter_mut().zip(&self.shapes) {
            *o = s.value(t_s) as f32;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::FemError;
    use crate::loads::{FixedDofs, ImposedDisplacement, NodalForce, SurfacePressure};

    #[test]
    fn free_nodes_have_no_record_and_later_conditions_win() {
        let bc = BoundaryConditions {
            fixed: vec![FixedDofs {
                nodes: vec![1],
                components: [true, true, false],
            }],
            displacements: vec![ImposedDisplacement {
                nodes: vec![1],
                components: [Some(0.5), None, None],
                shape: LoadShape::Ramp { duration_s: 1.0 },
            }],
            forces: vec![NodalForce {
                nodes: vec![2, 2],
                force_n: [1.0, 0.0, 0.0],
                shape: LoadShape::Step,
            }],
            pressures: vec![SurfacePressure {
                triangles: vec![[0, 1, 2]],
                pressure_pa: 10.0,
                shape: LoadShape::Ramp { duration_s: 1.0 },
            }],
            gravity_m_s2: None,
        };
        let c = CompiledLoads::new(&bc, 4, 1000).unwrap();
        assert_eq!(
            c.shapes,
            vec![LoadShape::Ramp { duration_s: 1.0 }, LoadShape::Step]
        );
        assert_eq!(c.node_loads[3], NONE);
        let r1 = c.node_loads[1] as usize;
        // x imposed (shape 0), y fixed, z free.
        assert_eq!(c.node_loads[r1], IMPOSED | (FIXED << 2));
        assert_eq!(f32::from_bits(c.node_loads[r1 + 2]), 0.5);
        assert_eq!(c.node_loads[r1 + 6], 1);
        assert_eq!(c.node_loads[r1 + 7], 1000 + 3);
        let r2 = c.node_loads[2] as usize;
        assert_eq!((c.node_loads[r2 + 5], c.node_loads[r2 + 6]), (2, 1));
        assert_eq!(c.node_loads[r2 + 7], 1);
        assert_eq!(c.shape_values(0.25)[..2], [0.25, 1.0]);
    }

    #[test]
    fn bad_conditions_are_refused_like_the_cpu_solver() {
        let mut bc = BoundaryConditions::default();
        bc.fix_nodes(&[7]);
        assert!(matches!(
            CompiledLoads::new(&bc, 4, 0),
            Err(GpuError::Solver(FemError::BoundaryNodeOutOfRange {
                node: 7,
                ..
            }))
        ));
        let many = BoundaryConditions {
            forces: (0..=MAX_LOAD_SHAPES)
                .map(|i| NodalForce {
                    nodes: vec![0],
                    force_n: [1.0; 3],
                    shape: LoadShape::Ramp {
                        duration_s: 1.0 + i as f64,
                    },
                })
                .collect(),
            ..BoundaryConditions::default()
        };
        assert!(matches!(
            CompiledLoads::new(&many, 4, 0),
            Err(GpuError::TooManyLoadShapes { .. })
        ));
    }
}
