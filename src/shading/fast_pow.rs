//! `x^n`, `2^y` and `log2 x` in eight f32 lanes, with no libm call and no conversion
//! between integers and floats: the specular exponent, Beckmann's exponential and the spot
//! falloff of the lane kernels ([`super::lanes`]).
//!
//! - `log2 x`: the exponent field gives `e` (read as a float by writing it under the
//!   exponent of 2²³), the mantissa `m` is folded into `[√½, √2)`, and
//!   `log2 m = (2/ln 2) atanh t` with `t = (m − 1)/(m + 1)`, `|t| ≤ 0.1716`, summed to `t⁷/7`
//!   (the first term left out, `(2/ln 2) t⁹/9`, is below `4.2·10⁻⁸`).
//! - `2^y`: adding `1.5·2²³` rounds `y` to the nearest integer `k` in the low bits, leaving
//!   `|f| ≤ ½` for `y = k + f`; `2^k` is written into the exponent field and
//!   `2^f = e^(f ln 2)` is its Taylor series to the 6th power (the remainder is below
//!   `1.7·10⁻⁷` relative).
//! - `x^n = 2^(n log2 x)` for `x > 0`, `0` for `x ≤ 0`, `1` for `n = 0`.
//!
//! The rest is single-precision rounding. The bound the tests hold it to, against f64
//! `powf` over `x ∈ [0, 1]` and `n ∈ [0.5, 1000]` (every case the shading asks for: cosines
//! raised to a shininess or a spot exponent): `|error| ≤ 4·10⁻⁶ · x^n + 10⁻¹²`, that is a
//! relative error under 4 parts in a million wherever the power is above 10⁻⁶, and below
//! that an error no pixel can show (an 8-bit pixel's step is 1/255). The relative error
//! grows with `|n log2 x|`, because that product is rounded to single precision.

use wide::{f32x8, i32x8};

fn bits(x: f32x8) -> i32x8 {
    wide::bytemuck::cast(x)
}

fn float(x: i32x8) -> f32x8 {
    wide::bytemuck::cast(x)
}

/// `log2 x` for positive normal `x` (other lanes give unspecified finite values).
#[inline(always)]
pub(super) fn log2(x: f32x8) -> f32x8 {
    const TWO_23: f32 = 8_388_608.0;
    let b = bits(x);
    // The biased exponent, 0..=255, under 2²³'s exponent field reads as 2²³ + itself.
    let biased = float((b >> 23u32) | i32x8::splat(TWO_23.to_bits() as i32)) - (TWO_23 + 127.0);
    let mantissa = float((b & i32x8::splat(0x007f_ffff)) | i32x8::splat(1.0f32.to_bits() as i32));
    // Fold the mantissa into [√½, √2) so that |t| stays small.
    let big = mantissa.simd_gt(f32x8::splat(std::f32::consts::SQRT_2));
    let m = big.select(mantissa * 0.5, mantissa);
    let e = biased + (big & f32x8::ONE);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    const C: f32 = 2.0 / std::f32::consts::LN_2;
    let series = t2.mul_add(f32x8::splat(C / 7.0), f32x8::splat(C / 5.0));
    let series = t2.mul_add(series, f32x8::splat(C / 3.0));
    let series = t2.mul_add(series, f32x8::splat(C));
    t.mul_add(series, e)
}

/// `2^y`; lanes below −126 give 0, lanes above 127 give 2^127.
#[inline(always)]
pub(super) fn exp2(y: f32x8) -> f32x8 {
    const ROUND: f32 = 12_582_912.0; // 1.5·2²³
    let clamped = y.max(f32x8::splat(-126.0)).min(f32x8::splat(127.0));
    let shifted = clamped + ROUND;
    let k = shifted - ROUND;
    let f = (clamped - k) * std::f32::consts::LN_2;
    // e^f to f⁶/6!, by Horner.
    let mut p = f32x8::splat(1.0 / 720.0);
    for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
        p = p.mul_add(f, f32x8::splat(c));
    }
    // shifted's low bits hold k: 2^k's biased exponent is k + 127.
    let exponent = bits(shifted) - i32x8::splat(ROUND.to_bits() as i32 - 127);
    let scale = float(exponent << 23u32);
    y.simd_lt(f32x8::splat(-126.0)).select(f32x8::ZERO, p * scale)
}

/// `x^n` for `x ≤ 1` and `n ≥ 0`: 0 where `x ≤ 0` (and `n > 0`), 1 everywhere when `n = 0`
/// (as f64 `powf` gives for `0^0`).
#[inline(always)]
pub(super) fn pow(x: f32x8, n: f32) -> f32x8 {
    if n == 0.0 {
        return f32x8::ONE;
    }
    let positive = x.simd_gt(f32x8::ZERO);
    let safe = positive.select(x, f32x8::ONE);
    positive.select(exp2(log2(safe) * n), f32x8::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes(f: impl Fn(f32x8) -> f32x8, x: f32) -> f32 {
        f(f32x8::splat(x)).to_array()[0]
    }

    #[test]
    fn pow_is_within_its_stated_bound() {
        let mut worst = 0.0f64;
        for n in [0.5f32, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 32.0, 64.0, 100.0, 128.0, 500.0, 1000.0] {
            for i in 0..=20_000 {
                // Dense near 1, where highlights are, and spread down to 0.
                let x = 1.0 - (i as f32 / 20_000.0).powi(3);
                let want = (x as f64).powf(n as f64);
                let got = lanes(|v| pow(v, n), x) as f64;
                let err = (got - want).abs();
                assert!(err <= 4e-6 * want + 1e-12, "{x}^{n}: {got} vs {want}");
                if want > 1e-6 {
                    worst = worst.max(err / want);
                }
            }
        }
        assert!(worst > 0.0, "the comparison saw no rounding at all");
        eprintln!("worst relative error where x^n > 1e-6: {worst:e}");
    }

    #[test]
    fn pow_edge_cases() {
        assert_eq!(lanes(|v| pow(v, 7.0), 0.0), 0.0);
        assert_eq!(lanes(|v| pow(v, 7.0), -0.5), 0.0);
        assert_eq!(lanes(|v| pow(v, 0.0), 0.0), 1.0);
        assert_eq!(lanes(|v| pow(v, 30.0), 1.0), 1.0);
        assert_eq!(lanes(|v| pow(v, 1000.0), 1e-30), 0.0);
    }

    #[test]
    fn exp2_and_log2_against_libm() {
        for i in -2000..=2000 {
            let y = i as f32 * 0.0625 + 0.03;
            let want = (y as f64).exp2();
            let got = lanes(exp2, y) as f64;
            assert!((got - want).abs() <= 3e-7 * want, "2^{y}: {got} vs {want}");
        }
        assert_eq!(lanes(exp2, -200.0), 0.0);
        for i in 1..=4000 {
            let x = i as f32 * 0.37;
            let want = (x as f64).log2();
            let got = lanes(log2, x) as f64;
            assert!((got - want).abs() <= 3e-7 * want.abs().max(1.0), "log2 {x}: {got} vs {want}");
        }
    }
}
