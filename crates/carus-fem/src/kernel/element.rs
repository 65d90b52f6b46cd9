//! Element maths of TLED, written once over [`Num`]: deformation gradient,
//! Cauchy-Green tensor, stress of the isotropic decoupled laws, nodal forces
//! and Flanagan-Belytschko hourglass forces. Runs on one element in f64 (output
//! fields, energies, tests) and on 8-lane blocks in the step loop.

use super::lanes::Num;

/// A symmetric 3x3 tensor (xx, yy, zz, xy, yz, xz).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sym<S> {
    pub xx: S,
    pub yy: S,
    pub zz: S,
    pub xy: S,
    pub yz: S,
    pub xz: S,
}

impl<S: Num> Sym<S> {
    #[inline(always)]
    pub fn det(&self) -> S {
        self.xx * (self.yy * self.zz - self.yz * self.yz)
            - self.xy * (self.xy * self.zz - self.yz * self.xz)
            + self.xz * (self.xy * self.yz - self.yy * self.xz)
    }

    #[inline(always)]
    pub fn trace(&self) -> S {
        self.xx + self.yy + self.zz
    }

    /// Adjugate (= det * inverse).
    #[inline(always)]
    fn adjugate(&self) -> Sym<S> {
        Sym {
            xx: self.yy * self.zz - self.yz * self.yz,
            yy: self.xx * self.zz - self.xz * self.xz,
            zz: self.xx * self.yy - self.xy * self.xy,
            xy: self.xz * self.yz - self.xy * self.zz,
            yz: self.xy * self.xz - self.xx * self.yz,
            xz: self.xy * self.yz - self.yy * self.xz,
        }
    }

    /// Full row-major matrix.
    #[inline(always)]
    pub fn to_rows(&self) -> [[S; 3]; 3] {
        [
            [self.xx, self.xy, self.xz],
            [self.xy, self.yy, self.yz],
            [self.xz, self.yz, self.zz],
        ]
    }
}

impl Sym<f64> {
    pub fn from_mat(m: &[[f64; 3]; 3]) -> Self {
        Sym {
            xx: m[0][0],
            yy: m[1][1],
            zz: m[2][2],
            xy: 0.5 * (m[0][1] + m[1][0]),
            yz: 0.5 * (m[1][2] + m[2][1]),
            xz: 0.5 * (m[0][2] + m[2][0]),
        }
    }
}

/// Coefficients of the shared isotropic kernel:
/// W = c10 (I1bar - 3) + c01 (I2bar - 3) + kappa/2 (J - 1)^2.
#[derive(Clone, Copy, Debug)]
pub struct Coefficients<S> {
    pub c10: S,
    pub c01: S,
    pub kappa: S,
}

impl Coefficients<f64> {
    pub fn from_f64(k: [f64; 3]) -> Self {
        Coefficients {
            c10: k[0],
            c01: k[1],
            kappa: k[2],
        }
    }
}

/// F = I + sum_a u_a (dh_a/dX)^T: `F[i][j] = delta_ij + sum_a u_a[i] dh_a[j]`.
#[inline(always)]
pub fn deformation_gradient<S: Num, const N: usize>(
    u: &[[S; 3]; N],
    dh: &[[S; 3]; N],
) -> [[S; 3]; 3] {
    let mut f = [[S::splat(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = S::splat(if i == j { 1.0 } else { 0.0 });
            for a in 0..N {
                acc = u[a][i].mul_add(dh[a][j], acc);
            }
            f[i][j] = acc;
        }
    }
    f
}

#[inline(always)]
pub fn det3<S: Num>(f: &[[S; 3]; 3]) -> S {
    f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1])
        - f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0])
        + f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0])
}

/// C = F^T F.
#[inline(always)]
pub fn right_cauchy_green<S: Num>(f: &[[S; 3]; 3]) -> Sym<S> {
    let col = |i: usize, j: usize| f[0][i].mul_add(f[0][j], f[1][i].mul_add(f[1][j], f[2][i] * f[2][j]));
    Sym {
        xx: col(0, 0),
        yy: col(1, 1),
        zz: col(2, 2),
        xy: col(0, 1),
        yz: col(1, 2),
        xz: col(0, 2),
    }
}

/// Second Piola-Kirchhoff stress of the decoupled isotropic law.
/// `j` = det F of the element; `j_vol` = the dilatation whose pressure
/// kappa (j_vol - 1) acts: `j` itself, or the averaged nodal value of T4ANP
/// (Joldes, Wittek & Miller 2009), which replaces the volumetric part only.
#[inline(always)]
pub fn second_piola_kirchhoff<S: Num>(c: &Sym<S>, j: S, j_vol: S, k: &Coefficients<S>) -> Sym<S> {
    let one = S::splat(1.0);
    let two = S::splat(2.0);
    let third = S::splat(1.0 / 3.0);
    let inv_det_c = one / (j * j);
    let adj = c.adjugate();
    let ci = Sym {
        xx: adj.xx * inv_det_c,
        yy: adj.yy * inv_det_c,
        zz: adj.zz * inv_det_c,
        xy: adj.xy * inv_det_c,
        yz: adj.yz * inv_det_c,
        xz: adj.xz * inv_det_c,
    };
    let i1 = c.trace();
    let tr_c2 =
        c.xx * c.xx + c.yy * c.yy + c.zz * c.zz + two * (c.xy * c.xy + c.yz * c.yz + c.xz * c.xz);
    let i2 = S::splat(0.5) * (i1 * i1 - tr_c2);
    let y = j.inv_cbrt();
    let y2 = y * y;
    // d(I1bar)/dC = J^-2/3 (I - I1/3 C^-1); d(I2bar)/dC = J^-4/3 (I1 I - C - 2 I2/3 C^-1)
    let a1 = two * k.c10 * y2;
    let a2 = two * k.c01 * y2 * y2;
    let p_vol = j * k.kappa * (j_vol - one);
    let ci_coef = p_vol - a1 * i1 * third - a2 * two * third * i2;
    let diag = a1 + a2 * i1;
    Sym {
        xx: diag - a2 * c.xx + ci_coef * ci.xx,
        yy: diag - a2 * c.yy + ci_coef * ci.yy,
        zz: diag - a2 * c.zz + ci_coef * ci.zz,
        xy: -a2 * c.xy + ci_coef * ci.xy,
        yz: -a2 * c.yz + ci_coef * ci.yz,
        xz: -a2 * c.xz + ci_coef * ci.xz,
    }
}

/// Strain energy per reference volume of the same law (j_vol as above).
#[inline(always)]
pub fn strain_energy_density<S: Num>(c: &Sym<S>, j: S, j_vol: S, k: &Coefficients<S>) -> S {
    let two = S::splat(2.0);
    let three = S::splat(3.0);
    let i1 = c.trace();
    let tr_c2 =
        c.xx * c.xx + c.yy * c.yy + c.zz * c.zz + two * (c.xy * c.xy + c.yz * c.yz + c.xz * c.xz);
    let i2 = S::splat(0.5) * (i1 * i1 - tr_c2);
    let y = j.inv_cbrt();
    let y2 = y * y;
    let dv = j_vol - S::splat(1.0);
    k.c10 * (y2 * i1 - three) + k.c01 * (y2 * y2 * i2 - three) + S::splat(0.5) * k.kappa * dv * dv
}

/// Nodal forces f_a = w F S dh_a, w the element volume (NiftySim:
/// Fe = 8 detJ X S dh^T, the same on parallelepipeds).
#[inline(always)]
pub fn stress_forces<S: Num, const N: usize>(
    f: &[[S; 3]; 3],
    s: &Sym<S>,
    dh: &[[S; 3]; N],
    w: S,
) -> [[S; 3]; N] {
    let sr = s.to_rows();
    let mut p = [[S::splat(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            p[i][j] = w * f[i][0].mul_add(sr[0][j], f[i][1].mul_add(sr[1][j], f[i][2] * sr[2][j]));
        }
    }
    let mut out = [[S::splat(0.0); 3]; N];
    for a in 0..N {
        for i in 0..3 {
            out[a][i] = p[i][0].mul_add(dh[a][0], p[i][1].mul_add(dh[a][1], p[i][2] * dh[a][2]));
        }
    }
    out
}

/// Hourglass mode amplitudes q_g,c = sum_a s_g,a u_a,c with s = sqrt(k) gamma.
#[inline(always)]
pub fn hourglass_amplitudes<S: Num, const N: usize>(
    u: &[[S; 3]; N],
    hg: &[[S; N]; 4],
) -> [[S; 3]; 4] {
    let mut q = [[S::splat(0.0); 3]; 4];
    for g in 0..4 {
        for c in 0..3 {
            let mut acc = S::splat(0.0);
            for a in 0..N {
                acc = hg[g][a].mul_add(u[a][c], acc);
            }
            q[g][c] = acc;
        }
    }
    q
}

/// Adds the hourglass forces k gamma gamma^T u per component
/// (Flanagan & Belytschko 1981 stiffness form as in NiftySim).
#[inline(always)]
pub fn add_hourglass_forces<S: Num, const N: usize>(
    forces: &mut [[S; 3]; N],
    q: &[[S; 3]; 4],
    hg: &[[S; N]; 4],
) {
    for a in 0..N {
        for c in 0..3 {
            let mut acc = forces[a][c];
            for g in 0..4 {
                acc = hg[g][a].mul_add(q[g][c], acc);
            }
            forces[a][c] = acc;
        }
    }
}

/// The whole element: internal nodal forces and J = det F.
/// `j_vol`: None for the standard element, Some(J averaged) for T4ANP.
#[inline(always)]
pub fn internal_forces<S: Num, const N: usize>(
    u: &[[S; 3]; N],
    dh: &[[S; 3]; N],
    w: S,
    k: &Coefficients<S>,
    j_vol: Option<S>,
    hg: Option<&[[S; N]; 4]>,
) -> ([[S; 3]; N], S) {
    let f = deformation_gradient(u, dh);
    let j = det3(&f);
    let c = right_cauchy_green(&f);
    let s = second_piola_kirchhoff(&c, j, j_vol.unwrap_or(j), k);
    let mut forces = stress_forces(&f, &s, dh, w);
    if let Some(hg) = hg {
        let q = hourglass_amplitudes(u, hg);
        add_hourglass_forces(&mut forces, &q, hg);
    }
    (forces, j)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::lanes::{Lanes, LANES};
    use proptest::prelude::*;

    /// Unit-cube T4 (0,0,0),(1,0,0),(0,1,0),(0,0,1) shape derivatives.
    fn unit_tet_dh() -> [[f64; 3]; 4] {
        [
            [-1.0, -1.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    }

    proptest! {
        /// An affine displacement u = (F - I) X gives back exactly F.
        #[test]
        fn deformation_gradient_of_affine_field(g in proptest::array::uniform9(-0.5f64..0.5)) {
            let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let mut u = [[0.0; 3]; 4];
            for a in 0..4 {
                for i in 0..3 {
                    u[a][i] = (0..3).map(|j| g[i * 3 + j] * x[a][j]).sum();
                }
            }
            let f = deformation_gradient(&u, &unit_tet_dh());
            for i in 0..3 {
                for j in 0..3 {
                    let expected = g[i * 3 + j] + if i == j { 1.0 } else { 0.0 };
                    prop_assert!((f[i][j] - expected).abs() < 1e-12);
                }
            }
        }

        /// The internal forces of any element sum to zero (equilibrium) and
        /// the 8-lane kernel gives the scalar result bit for bit.
        #[test]
        fn forces_balance_and_lanes_match_scalar(u in proptest::array::uniform4(proptest::array::uniform3(-0.1f64..0.1))) {
            let k = Coefficients { c10: 500.0, c01: 100.0, kappa: 5e4 };
            let (f, j) = internal_forces(&u, &unit_tet_dh(), 1.0 / 6.0, &k, None, None);
            prop_assert!(j > 0.0);
            for c in 0..3 {
                let sum: f64 = f.iter().map(|fa| fa[c]).sum();
                let scale: f64 = f.iter().map(|fa| fa[c].abs()).sum::<f64>() + 1e-12;
                prop_assert!(sum.abs() < 1e-12 * scale.max(1.0));
            }
            let lu = u.map(|ua| ua.map(|v| Lanes([v; LANES])));
            let ldh = unit_tet_dh().map(|d| d.map(|v| Lanes([v; LANES])));
            let lk = Coefficients { c10: Lanes([500.0; LANES]), c01: Lanes([100.0; LANES]), kappa: Lanes([5e4; LANES]) };
            let (lf, lj) = internal_forces(&lu, &ldh, Lanes([1.0 / 6.0; LANES]), &lk, None, None);
            for l in 0..LANES {
                prop_assert_eq!(lj.0[l], j);
                for a in 0..4 {
                    for c in 0..3 {
                        prop_assert_eq!(lf[a][c].0[l], f[a][c]);
                    }
                }
            }
        }
    }

    #[test]
    fn rigid_translation_gives_no_force() {
        let k = Coefficients {
            c10: 500.0,
            c01: 0.0,
            kappa: 5e4,
        };
        let u = [[0.3, -0.2, 0.1]; 4];
        let (f, j) = internal_forces(&u, &unit_tet_dh(), 1.0 / 6.0, &k, None, None);
        assert!((j - 1.0).abs() < 1e-15);
        for fa in f {
            for v in fa {
                assert!(v.abs() < 1e-9, "{v}");
            }
        }
    }
}
