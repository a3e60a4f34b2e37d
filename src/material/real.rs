//! The scalar type a law is evaluated in: `f64` for one point, or a pack of points evaluated
//! at once (the lane kernel's four SIMD lanes). Every law is written once, generic over it, so
//! the one-cell and the lane kernels compute the same formulas.

use std::ops::{Add, Div, Mul, Neg, Sub};

pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The constant `x` (in every lane).
    fn splat(x: f64) -> Self;
    fn ln(self) -> Self;
    fn powf(self, e: f64) -> Self;
    /// `self · b + c`, fused where the target has it.
    fn mul_add(self, b: Self, c: Self) -> Self;
    /// Lane by lane: `a` where `self ≥ bound`, else `b`.
    fn select_ge(self, bound: Self, a: Self, b: Self) -> Self;
}

impl Real for f64 {
    #[inline(always)]
    fn splat(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn ln(self) -> f64 {
        f64::ln(self)
    }
    #[inline(always)]
    fn powf(self, e: f64) -> f64 {
        f64::powf(self, e)
    }
    #[inline(always)]
    fn mul_add(self, b: f64, c: f64) -> f64 {
        f64::mul_add(self, b, c)
    }
    #[inline(always)]
    fn select_ge(self, bound: f64, a: f64, b: f64) -> f64 {
        if self >= bound { a } else { b }
    }
}
