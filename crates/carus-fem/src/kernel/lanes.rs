//! Scalar types of the hot loops and their 8-lane bundles.
//!
//! The element maths is written once over [`Num`] and runs either on one
//! element (`f64`, for output fields and tests) or on eight elements at a
//! time ([`Lanes`], the structure-of-arrays blocks), where every operation is
//! a plain loop over eight lanes that LLVM turns into one AVX2 instruction
//! (f32) or two (f64) inside the `#[target_feature]` entry points.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// Elements per structure-of-arrays block: one 256-bit register of f32.
pub const LANES: usize = 8;

/// A floating-point type the kernels run in (f32 or f64).
pub trait Real:
    Copy
    + Send
    + Sync
    + Default
    + PartialOrd
    + Debug
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
{
    /// Newton steps that take the bit-trick seed of x^(-1/3) to full precision.
    const CBRT_NEWTON_STEPS: usize;
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    /// self * a + b rounded once (one FMA instruction where the target has
    /// it; the inner products of the kernels are chains of these).
    fn mul_add(self, a: Self, b: Self) -> Self;
    fn is_finite(self) -> bool;
    /// A first guess of x^(-1/3) within a few per cent, from the bit pattern
    /// (branch-free integer arithmetic, so it vectorises; no libm call).
    fn inv_cbrt_seed(self) -> Self;
}

impl Real for f32 {
    const CBRT_NEWTON_STEPS: usize = 4;
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f32::mul_add(self, a, b)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn inv_cbrt_seed(self) -> Self {
        // bits(x^(-1/3)) ~ 4/3 bits(1) - bits(x)/3 (exponent arithmetic).
        f32::from_bits(0x54a2_fa8c_u32.wrapping_sub(self.to_bits() / 3))
    }
}

impl Real for f64 {
    const CBRT_NEWTON_STEPS: usize = 5;
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f64::mul_add(self, a, b)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[inline(always)]
    fn inv_cbrt_seed(self) -> Self {
        f64::from_bits(0x553e_f0ff_289d_d796_u64.wrapping_sub(self.to_bits() / 3))
    }
}

/// What the element maths needs of a number: field operations, a square
/// root and x^(-1/3).
pub trait Num:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    fn splat(x: f64) -> Self;
    fn sqrt(self) -> Self;
    /// self * a + b rounded once.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// x^(-1/3) for x > 0 (the isochoric factor J^(-1/3)); garbage, never a
    /// trap, for x <= 0, which the callers detect through J.
    fn inv_cbrt(self) -> Self;
}

#[inline(always)]
fn newton_inv_cbrt<S: Num>(x: S, mut y: S, steps: usize) -> S {
    let third = S::splat(1.0 / 3.0);
    let four = S::splat(4.0);
    for _ in 0..steps {
        y = y * (four - x * y * y * y) * third;
    }
    y
}

macro_rules! num_for_real {
    ($t:ty) => {
        impl Num for $t {
            #[inline(always)]
            fn splat(x: f64) -> Self {
                <$t as Real>::from_f64(x)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t as Real>::sqrt(self)
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                <$t as Real>::mul_add(self, a, b)
            }
            #[inline(always)]
            fn inv_cbrt(self) -> Self {
                newton_inv_cbrt(self, self.inv_cbrt_seed(), <$t as Real>::CBRT_NEWTON_STEPS)
            }
        }
    };
}
num_for_real!(f32);
num_for_real!(f64);

/// Eight values of one field for the eight elements of a block.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Lanes<T>(pub [T; LANES]);

impl<T: Real> Lanes<T> {
    #[inline(always)]
    pub fn load(src: &[T]) -> Self {
        let mut v = [T::default(); LANES];
        v.copy_from_slice(&src[..LANES]);
        Lanes(v)
    }
    #[inline(always)]
    pub fn store(self, dst: &mut [T]) {
        dst[..LANES].copy_from_slice(&self.0);
    }
}

/// Views a lane-major block slice `[T; N * M * LANES]` as `[[Lanes<T>; M]; N]`
/// without copying. Panics if the slice is shorter.
#[inline(always)]
pub fn block_view<T: Real, const N: usize, const M: usize>(s: &[T]) -> &[[Lanes<T>; M]; N] {
    let s = &s[..N * M * LANES];
    // SAFETY: `Lanes<T>` is `repr(transparent)` over `[T; LANES]`, so
    // `[[Lanes<T>; M]; N]` has the size and alignment of `[T; N * M * LANES]`,
    // which the slice above provides.
    unsafe { &*(s.as_ptr() as *const [[Lanes<T>; M]; N]) }
}

/// Mutable form of [`block_view`].
#[inline(always)]
pub fn block_view_mut<T: Real, const N: usize, const M: usize>(
    s: &mut [T],
) -> &mut [[Lanes<T>; M]; N] {
    let s = &mut s[..N * M * LANES];
    // SAFETY: as in `block_view`; the exclusive borrow is carried over.
    unsafe { &mut *(s.as_mut_ptr() as *mut [[Lanes<T>; M]; N]) }
}

macro_rules! lanes_binop {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<T: Real> $tr for Lanes<T> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..LANES {
                    r[l] = self.0[l] $op o.0[l];
                }
                Lanes(r)
            }
        }
    };
}
lanes_binop!(Add, add, +);
lanes_binop!(Sub, sub, -);
lanes_binop!(Mul, mul, *);
lanes_binop!(Div, div, /);

impl<T: Real> Neg for Lanes<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = -*v;
        }
        Lanes(r)
    }
}

impl<T: Real> Num for Lanes<T> {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Lanes([T::from_f64(x); LANES])
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = v.sqrt();
        }
        Lanes(r)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        let mut r = self.0;
        for l in 0..LANES {
            r[l] = self.0[l].mul_add(a.0[l], b.0[l]);
        }
        Lanes(r)
    }
    #[inline(always)]
    fn inv_cbrt(self) -> Self {
        let mut seed = self.0;
        for v in seed.iter_mut() {
            *v = v.inv_cbrt_seed();
        }
        newton_inv_cbrt(self, Lanes(seed), T::CBRT_NEWTON_STEPS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn inv_cbrt_f64_is_accurate(x in 1e-6f64..1e6) {
            let y = Num::inv_cbrt(x);
            prop_assert!((y - x.powf(-1.0 / 3.0)).abs() <= 1e-14 * x.powf(-1.0 / 3.0));
        }

        #[test]
        fn inv_cbrt_f32_is_accurate(x in 1e-4f32..1e4) {
            let y = Num::inv_cbrt(x);
            let exact = (x as f64).powf(-1.0 / 3.0);
            prop_assert!(((y as f64) - exact).abs() <= 1e-6 * exact);
        }

        #[test]
        fn lanes_match_scalar(x in proptest::array::uniform8(0.01f64..100.0)) {
            let v = Lanes(x).inv_cbrt();
            for l in 0..LANES {
                prop_assert_eq!(v.0[l], Num::inv_cbrt(x[l]));
            }
        }
    }
}
