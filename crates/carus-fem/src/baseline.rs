//! A straightforward single-threaded TLED, kept plain on purpose.
//!
//! This is the yardstick of `carus bench tled` (issue 2: "at least 5 times
//! faster than a straightforward single-threaded scalar implementation of the
//! same algorithm, measured in one run") and an independent cross-check of the
//! optimised solver. It is written from the formulation in DESIGN.md
//! ("Reference implementation to compare against", NiftySim), not from the
//! optimised code: an array of element structures in f64, one thread, no
//! explicit SIMD, element forces scatter-added straight into the node forces.
//!
//! - Neo-Hookean W = mu/2 (I1bar - 3) + kappa/2 (J - 1)^2, so
//!   S = mu J^(-2/3) (I - I1/3 C^-1) + kappa J (J - 1) C^-1.
//! - H8: one-point integration with the Flanagan-Belytschko uniform gradient
//!   (the element average of dh/dX, exact by 2x2x2 Gauss) and stiffness
//!   hourglass control f_HG = k gamma gamma^T u per component,
//!   gamma = Gamma - (dh/dX)(X^T Gamma), k = HGKappa V (lambda + 2 mu)
//!   sum((dh/dX)^2) / 8.
//! - T4: constant-strain tetrahedron.
//! - Lumped masses rho V / 8 (H8) and rho V / 4 (T4); central difference with
//!   mass-proportional damping alpha:
//!   u+ = [dt^2 (R - F(u)) / M + 2 u - (1 - alpha dt / 2) u-] / (1 + alpha dt / 2).

use thiserror::Error;

use crate::mesh::{ElementKind, Mesh};

/// Why the baseline solver could not be built or could not step.
#[derive(Debug, Error, PartialEq)]
pub enum BaselineError {
    /// An element of the input mesh has non-positive volume.
    #[error("element {element} has non-positive volume {volume_m3:e} m^3; fix its node order or geometry")]
    DegenerateElement { element: usize, volume_m3: f64 },
    /// An element turned inside out during the run.
    #[error("element {element} inverted (J = {jacobian:e}) at step {step}; reduce the time step or the load")]
    InvertedElement { element: usize, jacobian: f64, step: u64 },
    /// A node index in a boundary condition is outside the mesh.
    #[error("boundary node {node} is outside the mesh of {node_count} nodes")]
    UnknownNode { node: u32, node_count: usize },
}

/// Material, element and time-integration parameters of a baseline run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaselineParameters {
    pub shear_modulus_pa: f64,
    pub bulk_modulus_pa: f64,
    pub density_kg_m3: f64,
    /// NiftySim's HGKappa; 0 switches hourglass control off. Ignored for T4.
    pub hourglass_coefficient: f64,
    /// Mass-proportional damping alpha, 1/s.
    pub damping_per_s: f64,
    pub dt_s: f64,
}

/// A displacement boundary condition on one node: each component either
/// free (`None`) or held at `value * load_factor` (metres at full load).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeConstraint {
    pub node: u32,
    pub displacement_m: [Option<f64>; 3],
}

/// One element as a plain structure: its nodes and reference-configuration
/// data.
#[derive(Debug, Clone)]
struct Element<const N: usize> {
    nodes: [usize; N],
    volume_m3: f64,
    /// dh_a/dX_i, reference configuration.
    dh_dx: [[f64; 3]; N],
    /// Hourglass shape vectors gamma (8 x 4) and stiffness k (H8 only).
    hourglass: Option<([[f64; 4]; N], f64)>,
}

#[derive(Debug, Clone)]
enum Elements {
    Hexahedra(Vec<Element<8>>),
    Tetrahedra(Vec<Element<4>>),
}

/// The plain TLED solver: model data and state together, as a first
/// implementation would write them.
#[derive(Debug, Clone)]
pub struct BaselineSolver {
    params: BaselineParameters,
    elements: Elements,
    mass_kg: Vec<f64>,
    constraints: Vec<NodeConstraint>,
    displacement: Vec<[f64; 3]>,
    previous_displacement: Vec<[f64; 3]>,
    force: Vec<[f64; 3]>,
    steps: u64,
}

impl BaselineSolver {
    /// Precomputes volumes, shape derivatives, hourglass vectors and masses.
    pub fn new(
        mesh: &Mesh,
        params: BaselineParameters,
        constraints: Vec<NodeConstraint>,
    ) -> Result<BaselineSolver, BaselineError> {
        let node_count = mesh.node_count();
        if let Some(c) = constraints.iter().find(|c| c.node as usize >= node_count) {
            return Err(BaselineError::UnknownNode { node: c.node, node_count });
        }
        let mut mass_kg = vec![0.0; node_count];
        let elements = match mesh.kind {
            ElementKind::H8 => {
                let mut hexahedra = Vec::with_capacity(mesh.element_count());
                for (e, nodes) in mesh.elements().enumerate() {
                    let element = hexahedron(mesh, nodes, &params)
                        .ok_or(BaselineError::DegenerateElement { element: e, volume_m3: 0.0 })?;
                    if element.volume_m3 <= 0.0 {
                        return Err(BaselineError::DegenerateElement {
                            element: e,
                            volume_m3: element.volume_m3,
                        });
                    }
                    for n in element.nodes {
                        mass_kg[n] += params.density_kg_m3 * element.volume_m3 / 8.0;
                    }
                    hexahedra.push(element);
                }
                Elements::Hexahedra(hexahedra)
            }
            ElementKind::T4 => {
                let mut tetrahedra = Vec::with_capacity(mesh.element_count());
                for (e, nodes) in mesh.elements().enumerate() {
                    let element = tetrahedron(mesh, nodes);
                    if element.volume_m3 <= 0.0 {
                        return Err(BaselineError::DegenerateElement {
                            element: e,
                            volume_m3: element.volume_m3,
                        });
                    }
                    for n in element.nodes {
                        mass_kg[n] += params.density_kg_m3 * element.volume_m3 / 4.0;
                    }
                    tetrahedra.push(element);
                }
                Elements::Tetrahedra(tetrahedra)
            }
        };
        Ok(BaselineSolver {
            params,
            elements,
            mass_kg,
            constraints,
            displacement: vec![[0.0; 3]; node_count],
            previous_displacement: vec![[0.0; 3]; node_count],
            force: vec![[0.0; 3]; node_count],
            steps: 0,
        })
    }

    /// One central-difference step; the constrained components take their
    /// values at `load_factor` (the load shape's value at the new time).
    pub fn step(&mut self, load_factor: f64) -> Result<(), BaselineError> {
        self.compute_internal_forces()?;
        let BaselineParameters { dt_s: dt, damping_per_s: alpha, .. } = self.params;
        let damped = 1.0 - 0.5 * alpha * dt;
        let scale = 1.0 / (1.0 + 0.5 * alpha * dt);
        for n in 0..self.displacement.len() {
            for i in 0..3 {
                let u = self.displacement[n][i];
                let acceleration = -self.force[n][i] / self.mass_kg[n];
                let next = (dt * dt * acceleration + 2.0 * u - damped * self.previous_displacement[n][i]) * scale;
                self.previous_displacement[n][i] = u;
                self.displacement[n][i] = next;
            }
        }
        for c in &self.constraints {
            for i in 0..3 {
                if let Some(value) = c.displacement_m[i] {
                    self.displacement[c.node as usize][i] = value * load_factor;
                }
            }
        }
        self.steps += 1;
        Ok(())
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Current node displacements, metres.
    pub fn displacements(&self) -> &[[f64; 3]] {
        &self.displacement
    }

    /// Lumped node masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.mass_kg
    }

    /// Sum of the internal forces F(u) at the current displacements over
    /// `nodes`: the force the supports exert on the body at rest.
    pub fn reaction_force(&mut self, nodes: &[u32]) -> Result<[f64; 3], BaselineError> {
        self.compute_internal_forces()?;
        let mut total = [0.0; 3];
        for n in nodes {
            for i in 0..3 {
                total[i] += self.force[*n as usize][i];
            }
        }
        Ok(total)
    }

    /// Internal node forces F(u) at the current displacements, newtons.
    pub fn internal_forces(&mut self) -> Result<&[[f64; 3]], BaselineError> {
        self.compute_internal_forces()?;
        Ok(&self.force)
    }

    /// Stored energy (strain plus hourglass) at the current displacements, J.
    pub fn stored_energy_j(&self) -> f64 {
        let mut energy = 0.0;
        let mut add = |nodes: &[usize], volume: f64, dh_dx: &[[f64; 3]], hourglass: Option<(&[[f64; 4]], f64)>| {
            let f = deformation_gradient(nodes, dh_dx, &self.displacement);
            energy += volume * strain_energy_density(&f, &self.params);
            if let Some((gamma, k)) = hourglass {
                for i in 0..3 {
                    for m in 0..4 {
                        let h: f64 = nodes.iter().zip(gamma).map(|(n, g)| g[m] * self.displacement[*n][i]).sum();
                        energy += 0.5 * k * h * h;
                    }
                }
            }
        };
        match &self.elements {
            Elements::Hexahedra(list) => {
                for el in list {
                    add(&el.nodes, el.volume_m3, &el.dh_dx, el.hourglass.as_ref().map(|(g, k)| (&g[..], *k)));
                }
            }
            Elements::Tetrahedra(list) => {
                for el in list {
                    add(&el.nodes, el.volume_m3, &el.dh_dx, None);
                }
            }
        }
        energy
    }

    /// Overwrites the current and previous displacements (a state at rest).
    pub fn set_displacements(&mut self, displacements_m: &[[f64; 3]]) {
        self.displacement.copy_from_slice(displacements_m);
        self.previous_displacement.copy_from_slice(displacements_m);
    }

    fn compute_internal_forces(&mut self) -> Result<(), BaselineError> {
        for f in &mut self.force {
            *f = [0.0; 3];
        }
        let step = self.steps;
        match &self.elements {
            Elements::Hexahedra(list) => {
                for (e, el) in list.iter().enumerate() {
                    add_element_forces(el, &self.params, &self.displacement, &mut self.force)
                        .map_err(|jacobian| BaselineError::InvertedElement { element: e, jacobian, step })?;
                }
            }
            Elements::Tetrahedra(list) => {
                for (e, el) in list.iter().enumerate() {
                    add_element_forces(el, &self.params, &self.displacement, &mut self.force)
                        .map_err(|jacobian| BaselineError::InvertedElement { element: e, jacobian, step })?;
                }
            }
        }
        Ok(())
    }
}

/// Adds one element's nodal forces to `force`; Err(J) if it is inverted.
fn add_element_forces<const N: usize>(
    el: &Element<N>,
    params: &BaselineParameters,
    displacement: &[[f64; 3]],
    force: &mut [[f64; 3]],
) -> Result<(), f64> {
    let f = deformation_gradient(&el.nodes, &el.dh_dx, displacement);
    let s = second_piola_kirchhoff(&f, params)?;
    // First Piola-Kirchhoff P = F S; nodal force f_a = V P dh_a/dX.
    let p = matmul(&f, &s);
    for a in 0..N {
        let node = el.nodes[a];
        for i in 0..3 {
            let mut fi = 0.0;
            for j in 0..3 {
                fi += p[i][j] * el.dh_dx[a][j];
            }
            force[node][i] += el.volume_m3 * fi;
        }
    }
    if let Some((gamma, k)) = &el.hourglass {
        for i in 0..3 {
            let mut h = [0.0; 4];
            for a in 0..N {
                for m in 0..4 {
                    h[m] += gamma[a][m] * displacement[el.nodes[a]][i];
                }
            }
            for a in 0..N {
                let mut fi = 0.0;
                for m in 0..4 {
                    fi += gamma[a][m] * h[m];
                }
                force[el.nodes[a]][i] += k * fi;
            }
        }
    }
    Ok(())
}

/// F = I + sum_a u_a (dh_a/dX)^T.
fn deformation_gradient(nodes: &[usize], dh_dx: &[[f64; 3]], displacement: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut f = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for (n, d) in nodes.iter().zip(dh_dx) {
        let u = displacement[*n];
        for i in 0..3 {
            for j in 0..3 {
                f[i][j] += u[i] * d[j];
            }
        }
    }
    f
}

/// Neo-Hookean second Piola-Kirchhoff stress; Err(J) when J <= 0.
fn second_piola_kirchhoff(f: &[[f64; 3]; 3], params: &BaselineParameters) -> Result<[[f64; 3]; 3], f64> {
    let j = det(f);
    if !(j > 0.0) {
        return Err(j);
    }
    let c = matmul(&transpose(f), f);
    let c_inv = inverse(&c, j * j);
    let i1 = c[0][0] + c[1][1] + c[2][2];
    let mu = params.shear_modulus_pa;
    let kappa = params.bulk_modulus_pa;
    let deviatoric = mu * j.powf(-2.0 / 3.0);
    let volumetric = kappa * j * (j - 1.0);
    let mut s = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            let identity = if a == b { 1.0 } else { 0.0 };
            s[a][b] = deviatoric * (identity - i1 / 3.0 * c_inv[a][b]) + volumetric * c_inv[a][b];
        }
    }
    Ok(s)
}

fn strain_energy_density(f: &[[f64; 3]; 3], params: &BaselineParameters) -> f64 {
    let j = det(f);
    let c = matmul(&transpose(f), f);
    let i1 = c[0][0] + c[1][1] + c[2][2];
    0.5 * params.shear_modulus_pa * (j.powf(-2.0 / 3.0) * i1 - 3.0)
        + 0.5 * params.bulk_modulus_pa * (j - 1.0) * (j - 1.0)
}

/// Reference data of a hexahedron (VTK node order); None if a Gauss point
/// has a singular Jacobian.
fn hexahedron(mesh: &Mesh, nodes: &[u32], params: &BaselineParameters) -> Option<Element<8>> {
    // Natural coordinates of the VTK corners.
    const XI: [[f64; 3]; 8] = [
        [-1.0, -1.0, -1.0],
        [1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    let node_ids: [usize; 8] = std::array::from_fn(|a| nodes[a] as usize);
    let x: [[f64; 3]; 8] = node_ids.map(|n| mesh.nodes[n]);
    // Uniform gradient: integrate dh/dX det J over the element with 2x2x2
    // Gauss points (exact for the trilinear hexahedron).
    let g = 1.0 / 3f64.sqrt();
    let mut volume = 0.0;
    let mut integral = [[0.0; 3]; 8];
    for p in 0..8 {
        let point = XI[p].map(|s| s * g);
        let mut dn_dxi = [[0.0; 3]; 8];
        for a in 0..8 {
            for d in 0..3 {
                let mut value = XI[a][d] / 8.0;
                for o in 0..3 {
                    if o != d {
                        value *= 1.0 + XI[a][o] * point[o];
                    }
                }
                dn_dxi[a][d] = value;
            }
        }
        // jac[i][j] = dX_i / dxi_j
        let mut jac = [[0.0; 3]; 3];
        for a in 0..8 {
            for i in 0..3 {
                for j in 0..3 {
                    jac[i][j] += x[a][i] * dn_dxi[a][j];
                }
            }
        }
        let det_j = det(&jac);
        if det_j == 0.0 {
            return None;
        }
        let inv = inverse(&jac, det_j);
        volume += det_j;
        for a in 0..8 {
            for i in 0..3 {
                // dN/dX_i = sum_j dN/dxi_j dxi_j/dX_i
                let mut d = 0.0;
                for j in 0..3 {
                    d += dn_dxi[a][j] * inv[j][i];
                }
                integral[a][i] += d * det_j;
            }
        }
    }
    let dh_dx = integral.map(|row| row.map(|v| v / volume));
    // Flanagan-Belytschko base hourglass vectors: products of the corner signs.
    let base: [[f64; 4]; 8] =
        XI.map(|s| [s[0] * s[1], s[1] * s[2], s[0] * s[2], s[0] * s[1] * s[2]]);
    let mut gamma = base;
    for m in 0..4 {
        let mut x_dot = [0.0; 3];
        for a in 0..8 {
            for i in 0..3 {
                x_dot[i] += x[a][i] * base[a][m];
            }
        }
        for a in 0..8 {
            for i in 0..3 {
                gamma[a][m] -= dh_dx[a][i] * x_dot[i];
            }
        }
    }
    let lambda = params.bulk_modulus_pa - 2.0 * params.shear_modulus_pa / 3.0;
    let sum_sq: f64 = dh_dx.iter().flatten().map(|d| d * d).sum();
    let k = params.hourglass_coefficient * volume * (lambda + 2.0 * params.shear_modulus_pa) * sum_sq / 8.0;
    let hourglass = (params.hourglass_coefficient != 0.0).then_some((gamma, k));
    Some(Element { nodes: node_ids, volume_m3: volume, dh_dx, hourglass })
}

/// Reference data of a constant-strain tetrahedron.
fn tetrahedron(mesh: &Mesh, nodes: &[u32]) -> Element<4> {
    let node_ids: [usize; 4] = std::array::from_fn(|a| nodes[a] as usize);
    let x = node_ids.map(|n| mesh.nodes[n]);
    // jac[i][j] = dX_i / dxi_j with edges from node 0 as columns.
    let mut jac = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            jac[i][j] = x[j + 1][i] - x[0][i];
        }
    }
    let det_j = det(&jac);
    let volume = det_j / 6.0;
    let mut dh_dx = [[0.0; 3]; 4];
    if det_j != 0.0 {
        let inv = inverse(&jac, det_j);
        const DN_DXI: [[f64; 3]; 4] = [[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for a in 0..4 {
            for i in 0..3 {
                for j in 0..3 {
                    dh_dx[a][i] += DN_DXI[a][j] * inv[j][i];
                }
            }
        }
    }
    Element { nodes: node_ids, volume_m3: volume, dh_dx, hourglass: None }
}

fn det(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse from the adjugate, given the determinant.
fn inverse(m: &[[f64; 3]; 3], det: f64) -> [[f64; 3]; 3] {
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            // Cofactor of m[j][i].
            let (r0, r1) = ((j + 1) % 3, (j + 2) % 3);
            let (c0, c1) = ((i + 1) % 3, (i + 2) % 3);
            inv[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
    }
    inv
}

fn matmul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                c[i][j] += a[i][k] * b[k][j];
            }
        }
    }
    c
}

fn transpose(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{box_h8, box_t4};
    use proptest::prelude::*;

    /// V3's material (VALIDATION.md: mu = 1006.711409 Pa, kappa = 50 000 Pa).
    fn params(dt_s: f64) -> BaselineParameters {
        BaselineParameters {
            shear_modulus_pa: 1006.711409,
            bulk_modulus_pa: 50_000.0,
            density_kg_m3: 1000.0,
            hourglass_coefficient: 0.075,
            damping_per_s: 5.0,
            dt_s,
        }
    }

    /// A mesh with its interior and boundary nodes moved off the grid.
    fn distorted(mut mesh: Mesh, amplitude_m: f64) -> Mesh {
        for (n, p) in mesh.nodes.iter_mut().enumerate() {
            let phase = n as f64 * 0.7;
            p[0] += amplitude_m * phase.sin();
            p[1] += amplitude_m * (1.3 * phase).cos();
            p[2] += amplitude_m * (2.1 * phase).sin();
        }
        mesh
    }

    #[test]
    fn masses_sum_to_the_body_mass() {
        for mesh in [box_h8([0.1, 0.2, 0.3], [2, 3, 4]), box_t4([0.1, 0.2, 0.3], [2, 3, 4])] {
            let solver = BaselineSolver::new(&mesh, params(1e-3), vec![]).unwrap();
            let total: f64 = solver.masses().iter().sum();
            assert!((total - 1000.0 * 0.006).abs() < 1e-12);
        }
    }

    #[test]
    fn inverted_input_element_is_named() {
        let mut mesh = box_t4([1.0, 1.0, 1.0], [1, 1, 1]);
        mesh.connectivity.swap(4 * 3 + 1, 4 * 3 + 2);
        let err = BaselineSolver::new(&mesh, params(1e-3), vec![]).unwrap_err();
        assert!(matches!(err, BaselineError::DegenerateElement { element: 3, .. }));
    }

    #[test]
    fn unknown_boundary_node_is_refused() {
        let mesh = box_h8([1.0, 1.0, 1.0], [1, 1, 1]);
        let constraints = vec![NodeConstraint { node: 8, displacement_m: [Some(0.0); 3] }];
        let err = BaselineSolver::new(&mesh, params(1e-3), constraints).unwrap_err();
        assert_eq!(err, BaselineError::UnknownNode { node: 8, node_count: 8 });
    }

    /// Homogeneous stretch of one axis-aligned element: the face force equals
    /// the nominal stress of the neo-Hookean law times the reference area,
    /// P_xx = lambda_x S_xx, worked out by hand for a diagonal F.
    #[test]
    fn homogeneous_stretch_gives_the_hand_computed_face_force() {
        for mesh in [box_h8([0.1, 0.1, 0.1], [2, 2, 2]), box_t4([0.1, 0.1, 0.1], [2, 2, 2])] {
            let mut solver = BaselineSolver::new(&mesh, params(1e-3), vec![]).unwrap();
            let (lx, lt) = (1.2, 0.95);
            let u: Vec<[f64; 3]> =
                mesh.nodes.iter().map(|p| [(lx - 1.0) * p[0], (lt - 1.0) * p[1], (lt - 1.0) * p[2]]).collect();
            solver.set_displacements(&u);
            let (mu, kappa) = (1006.711409, 50_000.0);
            let j: f64 = lx * lt * lt;
            let i1 = lx * lx + 2.0 * lt * lt;
            let s_xx = mu * j.powf(-2.0 / 3.0) * (1.0 - i1 / 3.0 / (lx * lx)) + kappa * j * (j - 1.0) / (lx * lx);
            let expected = lx * s_xx * 0.01;
            let reaction = solver.reaction_force(&mesh.node_sets["x1"]).unwrap();
            assert!((reaction[0] - expected).abs() < 1e-10 * expected.abs(), "{reaction:?} vs {expected}");
            assert!(reaction[1].abs() < 1e-12 && reaction[2].abs() < 1e-12);
        }
    }

    proptest! {
        /// The internal forces are the gradient of the stored energy
        /// (strain + hourglass) on distorted meshes: checks kinematics,
        /// stress and hourglass forces together by central differences.
        #[test]
        fn forces_are_the_energy_gradient(seed in 0u64..1000, hex in any::<bool>()) {
            let base = if hex { box_h8([0.1, 0.1, 0.1], [2, 1, 1]) } else { box_t4([0.1, 0.1, 0.1], [1, 1, 1]) };
            let mesh = distorted(base, 0.01);
            let mut solver = BaselineSolver::new(&mesh, params(1e-3), vec![]).unwrap();
            let u: Vec<[f64; 3]> = (0..mesh.node_count())
                .map(|n| [0, 1, 2].map(|i| 0.01 * ((seed as f64 + 1.0) * (n * 3 + i + 1) as f64).sin()))
                .collect();
            solver.set_displacements(&u);
            let forces = solver.internal_forces().unwrap().to_vec();
            let h = 1e-7;
            for n in 0..mesh.node_count() {
                for i in 0..3 {
                    let mut probe = u.clone();
                    probe[n][i] += h;
                    solver.set_displacements(&probe);
                    let plus = solver.stored_energy_j();
                    probe[n][i] -= 2.0 * h;
                    solver.set_displacements(&probe);
                    let minus = solver.stored_energy_j();
                    let gradient = (plus - minus) / (2.0 * h);
                    let scale = forces.iter().flatten().fold(0.0f64, |m, f| m.max(f.abs()));
                    prop_assert!((gradient - forces[n][i]).abs() < 1e-5 * scale,
                        "node {} dof {}: {} vs {}", n, i, gradient, forces[n][i]);
                }
            }
        }

        /// A rigid rotation gives no internal force (objectivity), and the
        /// hourglass forces vanish for any affine field.
        #[test]
        fn rigid_rotation_is_force_free(angle in -1.5f64..1.5, hex in any::<bool>()) {
            let base = if hex { box_h8([0.1, 0.1, 0.1], [2, 2, 2]) } else { box_t4([0.1, 0.1, 0.1], [2, 2, 2]) };
            let mesh = distorted(base, 0.008);
            let mut solver = BaselineSolver::new(&mesh, params(1e-3), vec![]).unwrap();
            let (s, c) = angle.sin_cos();
            let u: Vec<[f64; 3]> = mesh.nodes.iter()
                .map(|p| [c * p[0] - s * p[1] - p[0], s * p[0] + c * p[1] - p[1], 0.0])
                .collect();
            solver.set_displacements(&u);
            let forces = solver.internal_forces().unwrap();
            for f in forces {
                for v in f {
                    prop_assert!(v.abs() < 1e-9, "force {}", v);
                }
            }
        }
    }

    /// With every node held, one step puts the nodes on their constraints
    /// scaled by the load factor, and free nodes at rest stay put.
    #[test]
    fn constraints_follow_the_load_factor() {
        let mesh = box_h8([0.1, 0.1, 0.1], [2, 2, 2]);
        let constraints = mesh.node_sets["x1"]
            .iter()
            .map(|n| NodeConstraint { node: *n, displacement_m: [Some(0.01), None, Some(0.0)] })
            .collect();
        let mut solver = BaselineSolver::new(&mesh, params(1e-3), constraints).unwrap();
        solver.step(0.5).unwrap();
        for n in &mesh.node_sets["x1"] {
            assert_eq!(solver.displacements()[*n as usize][0], 0.005);
        }
        assert_eq!(solver.displacements()[0], [0.0; 3]);
        assert_eq!(solver.steps(), 1);
    }

    #[test]
    fn stepping_reports_an_inverted_element() {
        let mesh = box_t4([0.1, 0.1, 0.1], [1, 1, 1]);
        // Push one face through the opposite one in a single step.
        let constraints = mesh.node_sets["x1"]
            .iter()
            .map(|n| NodeConstraint { node: *n, displacement_m: [Some(-0.2), None, None] })
            .collect();
        let mut solver = BaselineSolver::new(&mesh, params(1e-3), constraints).unwrap();
        solver.step(1.0).unwrap();
        let err = solver.step(1.0).unwrap_err();
        assert!(matches!(err, BaselineError::InvertedElement { step: 1, .. }));
    }
}
