//! Hyperelastic material laws.
//!
//! Every law gives the second Piola-Kirchhoff stress S from the right
//! Cauchy-Green tensor C (Total Lagrangian form, Miller et al. 2007) and the
//! small-strain Lame parameters that set the wave speed (critical time step)
//! and the hourglass stiffness. The isotropic laws here share one fast
//! kernel (Mooney-Rivlin with c01 = 0 is neo-Hookean); a transversely
//! isotropic law implements [`MaterialLaw`] and adds its own kernel.

use serde::{Deserialize, Serialize};

use crate::error::FemError;

/// A symmetric 3x3 tensor as a full matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// A hyperelastic strain-energy function.
pub trait MaterialLaw {
    /// Strain energy per reference volume W(C), J/m^3.
    fn strain_energy_density(&self, c: &Mat3) -> f64;
    /// Second Piola-Kirchhoff stress S = 2 dW/dC, Pa.
    fn second_piola_kirchhoff(&self, c: &Mat3) -> Mat3;
    /// Small-strain Lame parameters (lambda, mu), Pa.
    fn lame_parameters(&self) -> (f64, f64);
    /// Dilatational wave speed sqrt((lambda + 2 mu) / rho), m/s.
    fn dilatational_wave_speed(&self, density_kg_m3: f64) -> f64 {
        let (lambda, mu) = self.lame_parameters();
        ((lambda + 2.0 * mu) / density_kg_m3).sqrt()
    }
}

/// Decoupled neo-Hookean solid, W = mu/2 (I1bar - 3) + kappa/2 (J - 1)^2
/// (the form NiftySim uses; DESIGN.md "Reference implementation").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NeoHookean {
    pub shear_modulus_pa: f64,
    pub bulk_modulus_pa: f64,
}

impl NeoHookean {
    /// From Young's modulus and Poisson's ratio (linear-elastic relations
    /// mu = E / (2 (1 + nu)), kappa = E / (3 (1 - 2 nu))).
    pub fn from_young_poisson(young_pa: f64, poisson: f64) -> Result<Self, FemError> {
        let (mu, kappa) = shear_bulk_from_young_poisson(young_pa, poisson)?;
        Ok(NeoHookean {
            shear_modulus_pa: mu,
            bulk_modulus_pa: kappa,
        })
    }
}

/// Decoupled Mooney-Rivlin solid,
/// W = c10 (I1bar - 3) + c01 (I2bar - 3) + kappa/2 (J - 1)^2;
/// small-strain shear modulus mu = 2 (c10 + c01).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MooneyRivlin {
    pub c10_pa: f64,
    pub c01_pa: f64,
    pub bulk_modulus_pa: f64,
}

/// The material of a region, as scenario files write it
/// (`{ law = "neo_hookean", shear_modulus_pa = ..., bulk_modulus_pa = ... }`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum Material {
    NeoHookean(NeoHookean),
    MooneyRivlin(MooneyRivlin),
}

fn shear_bulk_from_young_poisson(young_pa: f64, poisson: f64) -> Result<(f64, f64), FemError> {
    if !(young_pa.is_finite() && young_pa > 0.0) {
        return Err(FemError::InvalidMaterial {
            reason: format!("Young's modulus must be positive, got {young_pa} Pa"),
        });
    }
    if !(poisson > -1.0 && poisson < 0.5) {
        return Err(FemError::InvalidMaterial {
            reason: format!("Poisson's ratio must lie in (-1, 0.5), got {poisson}; use bulk modulus for incompressibility"),
        });
    }
    Ok((
        young_pa / (2.0 * (1.0 + poisson)),
        young_pa / (3.0 * (1.0 - 2.0 * poisson)),
    ))
}

impl Material {
    /// Neo-Hookean from shear and bulk moduli.
    pub fn neo_hookean(shear_modulus_pa: f64, bulk_modulus_pa: f64) -> Self {
        Material::NeoHookean(NeoHookean {
            shear_modulus_pa,
            bulk_modulus_pa,
        })
    }

    /// Coefficients (c10, c01, kappa) of the shared isotropic kernel.
    pub fn kernel_coefficients(&self) -> [f64; 3] {
        match *self {
            Material::NeoHookean(m) => [m.shear_modulus_pa / 2.0, 0.0, m.bulk_modulus_pa],
            Material::MooneyRivlin(m) => [m.c10_pa, m.c01_pa, m.bulk_modulus_pa],
        }
    }

    /// Rejects non-physical parameters (the region is named by the caller).
    pub fn validate(&self) -> Result<(), FemError> {
        let [c10, c01, kappa] = self.kernel_coefficients();
        let ok = c10.is_finite()
            && c01.is_finite()
            && kappa.is_finite()
            && c10 + c01 > 0.0
            && c10 >= 0.0
            && c01 >= 0.0
            && kappa > 0.0;
        if ok {
            Ok(())
        } else {
            Err(FemError::InvalidMaterial {
                reason: format!("need c10, c01 >= 0 with a positive shear modulus and a positive bulk modulus, got c10 = {c10} Pa, c01 = {c01} Pa, kappa = {kappa} Pa"),
            })
        }
    }
}

/// The isotropic decoupled law evaluated in f64 (reference path; the block
/// kernel evaluates the same expressions, see `kernel::element`).
impl MaterialLaw for Material {
    fn strain_energy_density(&self, c: &Mat3) -> f64 {
        let k = crate::kernel::element::Coefficients::from_f64(self.kernel_coefficients());
        let c = crate::kernel::element::Sym::from_mat(c);
        let j = c.det().sqrt();
        crate::kernel::element::strain_energy_density(&c, j, j, &k)
    }

    fn second_piola_kirchhoff(&self, c: &Mat3) -> Mat3 {
        let k = crate::kernel::element::Coefficients::from_f64(self.kernel_coefficients());
        let c = crate::kernel::element::Sym::from_mat(c);
        let j = c.det().sqrt();
        crate::kernel::element::second_piola_kirchhoff(&c, j, j, &k).to_rows()
    }

    fn lame_parameters(&self) -> (f64, f64) {
        let [c10, c01, kappa] = self.kernel_coefficients();
        let mu = 2.0 * (c10 + c01);
        (kappa - 2.0 * mu / 3.0, mu)
    }
}

impl MaterialLaw for NeoHookean {
    fn strain_energy_density(&self, c: &Mat3) -> f64 {
        Material::NeoHookean(*self).strain_energy_density(c)
    }
    fn second_piola_kirchhoff(&self, c: &Mat3) -> Mat3 {
        Material::NeoHookean(*self).second_piola_kirchhoff(c)
    }
    fn lame_parameters(&self) -> (f64, f64) {
        Material::NeoHookean(*self).lame_parameters()
    }
}

impl MaterialLaw for MooneyRivlin {
    fn strain_energy_density(&self, c: &Mat3) -> f64 {
        Material::MooneyRivlin(*self).strain_energy_density(c)
    }
    fn second_piola_kirchhoff(&self, c: &Mat3) -> Mat3 {
        Material::MooneyRivlin(*self).second_piola_kirchhoff(c)
    }
    fn lame_parameters(&self) -> (f64, f64) {
        Material::MooneyRivlin(*self).lame_parameters()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn c_from_f(f: &Mat3) -> Mat3 {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| f[k][i] * f[k][j]).sum();
            }
        }
        c
    }

    fn deformation() -> impl Strategy<Value = Mat3> {
        proptest::array::uniform3(proptest::array::uniform3(-0.25f64..0.25)).prop_map(|d| {
            let mut f = d;
            for i in 0..3 {
                f[i][i] += 1.0;
            }
            f
        })
    }

    fn law() -> impl Strategy<Value = Material> {
        prop_oneof![
            (100.0f64..1e4, 1e3f64..1e5).prop_map(|(mu, k)| Material::neo_hookean(mu, k)),
            (50.0f64..5e3, 0.0f64..5e3, 1e3f64..1e5).prop_map(|(c10, c01, k)| {
                Material::MooneyRivlin(MooneyRivlin {
                    c10_pa: c10,
                    c01_pa: c01,
                    bulk_modulus_pa: k,
                })
            }),
        ]
    }

    proptest! {
        /// S = 2 dW/dC, checked by central differences on symmetric perturbations of C.
        #[test]
        fn stress_is_the_derivative_of_the_energy(f in deformation(), m in law()) {
            let c = c_from_f(&f);
            let s = m.second_piola_kirchhoff(&c);
            let h = 1e-6;
            for i in 0..3 {
                for j in i..3 {
                    let mut cp = c;
                    let mut cm = c;
                    cp[i][j] += h; cm[i][j] -= h;
                    if i != j { cp[j][i] += h; cm[j][i] -= h; }
                    let dw = (m.strain_energy_density(&cp) - m.strain_energy_density(&cm)) / (2.0 * h);
                    // dW along the symmetric direction = S_ij/2 * (1 or 2)
                    let expected = if i == j { s[i][j] / 2.0 } else { s[i][j] };
                    let scale = 1.0 + s.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
                    prop_assert!((dw - expected).abs() < 1e-5 * scale, "dW {} vs S {} at {},{}", dw, expected, i, j);
                }
            }
        }

        /// Rigid rotations give zero stress and zero energy.
        #[test]
        fn rigid_rotation_is_stress_free(ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in -1.0f64..1.0, angle in -3.0f64..3.0, m in law()) {
            let n = (ax * ax + ay * ay + az * az).sqrt().max(1e-3);
            let (x, y, z) = (ax / n, ay / n, az / n);
            let (s, c) = angle.sin_cos();
            let t = 1.0 - c;
            let r = [
                [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
            ];
            let cg = c_from_f(&r);
            let stress = m.second_piola_kirchhoff(&cg);
            for v in stress.iter().flatten() {
                prop_assert!(v.abs() < 1e-9 * m.kernel_coefficients()[2]);
            }
            prop_assert!(m.strain_energy_density(&cg).abs() < 1e-9 * m.kernel_coefficients()[2]);
        }
    }

    #[test]
    fn young_poisson_conversion_matches_validation_cube() {
        // VALIDATION.md V3: E = 3000 Pa, nu = 0.49 -> mu = 1006.711409 Pa, kappa = 50 000 Pa.
        let m = NeoHookean::from_young_poisson(3000.0, 0.49).unwrap();
        assert!((m.shear_modulus_pa - 1006.711409).abs() < 1e-6);
        assert!((m.bulk_modulus_pa - 50_000.0).abs() < 1e-6);
        assert!(NeoHookean::from_young_poisson(3000.0, 0.5).is_err());
        assert!(NeoHookean::from_young_poisson(-1.0, 0.3).is_err());
    }

    #[test]
    fn small_strain_lame_and_wave_speed() {
        let m = Material::neo_hookean(1000.0, 50_000.0);
        let (lambda, mu) = m.lame_parameters();
        assert_eq!(mu, 1000.0);
        assert!((lambda - (50_000.0 - 2000.0 / 3.0)).abs() < 1e-9);
        let c = m.dilatational_wave_speed(1000.0);
        assert!((c - ((lambda + 2.0 * mu) / 1000.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn serde_is_tagged_by_law() {
        let m = Material::neo_hookean(1.0, 2.0);
        let s = serde_json::to_string(&m).unwrap();
        assert!(s.contains("\"law\":\"neo_hookean\""), "{s}");
        let back: Material = serde_json::from_str(&s).unwrap();
        assert_eq!(back, m);
    }
}
