//! Closed-form uniaxial stress of the neo-Hookean law used by V1.
//!
//! W = mu/2 (I1bar - 3) + kappa/2 (J - 1)^2 gives the Cauchy stress
//! sigma = mu J^(-5/3) (b - I1/3 I) + kappa (J - 1) I. For a stretch lambda
//! along x with lateral stretch t (J = lambda t^2), uniaxial stress means
//! sigma_yy = sigma_zz = 0:
//!   mu J^(-5/3) (t^2 - (lambda^2 + 2 t^2) / 3) + kappa (J - 1) = 0,
//! solved for t; the nominal (first Piola-Kirchhoff) stress is then
//!   P_xx = J sigma_xx / lambda = t^2 sigma_xx,
//!   sigma_xx = mu J^(-5/3) (lambda^2 - (lambda^2 + 2 t^2) / 3) + kappa (J - 1).

/// Cauchy stress components (axial, lateral) for stretches (lambda, t).
fn cauchy_axial_lateral(stretch: f64, lateral: f64, mu: f64, kappa: f64) -> (f64, f64) {
    let j = stretch * lateral * lateral;
    let i1_third = (stretch * stretch + 2.0 * lateral * lateral) / 3.0;
    let deviatoric = mu * j.powf(-5.0 / 3.0);
    let pressure = kappa * (j - 1.0);
    (
        deviatoric * (stretch * stretch - i1_third) + pressure,
        deviatoric * (lateral * lateral - i1_third) + pressure,
    )
}

/// The lateral stretch that makes the lateral stress vanish. The lateral
/// stress rises monotonically with t (from -inf at t -> 0), so bisection on
/// a bracket that changes sign finds the one root.
pub fn uniaxial_lateral_stretch(stretch: f64, shear_modulus_pa: f64, bulk_modulus_pa: f64) -> f64 {
    let lateral_stress = |t: f64| cauchy_axial_lateral(stretch, t, shear_modulus_pa, bulk_modulus_pa).1;
    let (mut low, mut high) = (1e-3, 1.0);
    while lateral_stress(high) < 0.0 {
        high *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        if lateral_stress(mid) < 0.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high)
}

/// Nominal stress (force per reference area) of uniaxial stress at
/// `stretch`, Pa.
pub fn uniaxial_nominal_stress_pa(stretch: f64, shear_modulus_pa: f64, bulk_modulus_pa: f64) -> f64 {
    let t = uniaxial_lateral_stretch(stretch, shear_modulus_pa, bulk_modulus_pa);
    t * t * cauchy_axial_lateral(stretch, t, shear_modulus_pa, bulk_modulus_pa).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn incompressible_limit_is_the_textbook_formula() {
        // kappa -> infinity: t = lambda^(-1/2), P = mu (lambda - lambda^-2).
        let (mu, kappa) = (1000.0, 1e12);
        for stretch in [0.8, 1.1, 1.3, 2.0] {
            let expected = mu * (stretch - 1.0 / (stretch * stretch));
            let p = uniaxial_nominal_stress_pa(stretch, mu, kappa);
            assert!((p - expected).abs() < 1e-5 * expected.abs(), "{stretch}: {p} vs {expected}");
        }
    }

    #[test]
    fn small_strain_slope_is_youngs_modulus() {
        // E = 9 kappa mu / (3 kappa + mu) (VALIDATION.md V3: E = 3000 Pa).
        let (mu, kappa) = (1006.711409, 50_000.0);
        let e = 9.0 * kappa * mu / (3.0 * kappa + mu);
        let eps = 1e-6;
        let slope = uniaxial_nominal_stress_pa(1.0 + eps, mu, kappa) / eps;
        assert!((slope - e).abs() < 1e-4 * e);
        assert!((e - 3000.0).abs() < 1e-3);
    }

    proptest! {
        #[test]
        fn lateral_stress_vanishes(stretch in 0.5f64..2.0, mu in 10.0f64..1e5, ratio in 1.0f64..1e4) {
            let kappa = mu * ratio;
            let t = uniaxial_lateral_stretch(stretch, mu, kappa);
            let (axial, lateral) = cauchy_axial_lateral(stretch, t, mu, kappa);
            prop_assert!(lateral.abs() <= 1e-9 * axial.abs().max(mu));
            // Tension contracts sideways, compression bulges.
            prop_assert!((stretch - 1.0) * (t - 1.0) <= 0.0);
        }
    }
}
