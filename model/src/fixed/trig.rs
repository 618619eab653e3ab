//! sin and cos of a [`Rad`] (Q28) angle in [`Unit`] (Q30): reduction by the nearest multiple
//! of pi/2, then Taylor polynomials on [-pi/4, pi/4] (degree 9 / 10, Horner, 64-bit products;
//! truncation below 2e-9); the square root of a 64-bit value.
use super::q::{Rad, Unit, Q};

const FRAC_2_PI_Q30: i64 = 683565276; // 2/pi 2^30
const PI_2_Q30: i64 = 1686629713; // pi/2 2^30, truncated
const PI_2_LO_Q60: i64 = 70064198; // the rest of pi/2 below 2^-30, at Q60

/// `(sin x, cos x)`; any |x| < 8 rad (the format's range).
pub fn sin_cos(x: Rad) -> (Unit, Unit) {
    // k = round(x 2/pi); r = x - k pi/2 at Q30
    let xq = x.0 as i64; // Q28
    let k = ((xq * FRAC_2_PI_Q30) + (1i64 << 57)) >> 58;
    let r = (xq << 2) - k * PI_2_Q30 - ((k * PI_2_LO_Q60) >> 30); // Q30, |r| <= pi/4
                                                                  // |r| <= pi/4: every value below fits an i32 at Q30, so each product is one SMULL
    let r = r as i32;
    let mul = |a: i32, b: i32| ((a as i64 * b as i64 + (1 << 29)) >> 30) as i32;
    let u = mul(r, r); // r^2, Q30
    const ONE: i32 = 1 << 30;
    // sin r = r (1 - u/6 (1 - u/20 (1 - u/42 (1 - u/72))))
    const S: [i32; 4] = [178956971, 53687091, 25565282, 14913081]; // 2^30 / 6, 20, 42, 72
    let mut s = ONE - mul(u, S[3]);
    s = ONE - mul(mul(u, S[2]), s);
    s = ONE - mul(mul(u, S[1]), s);
    s = ONE - mul(mul(u, S[0]), s);
    let s = mul(r, s);
    // cos r = 1 - u/2 (1 - u/12 (1 - u/30 (1 - u/56 (1 - u/90))))
    const C: [i32; 5] = [536870912, 89478485, 35791394, 19173961, 11930465]; // 2^30 / 2, 12, 30, 56, 90
    let mut c = ONE - mul(u, C[4]);
    c = ONE - mul(mul(u, C[3]), c);
    c = ONE - mul(mul(u, C[2]), c);
    c = ONE - mul(mul(u, C[1]), c);
    // cos(0) = 2^30 exactly: Q30's +1 (the format holds +-2)
    c = ONE - mul(mul(u, C[0]), c);
    let (s, c) = (Q(s), Q(c));
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// floor(sqrt(v)) of a non-negative 64-bit value (digit by digit).
pub fn isqrt(v: u64) -> u64 {
    let mut rem = v;
    let mut res: u64 = 0;
    if v == 0 {
        return 0;
    }
    // the highest even bit at or below v's top bit
    let mut bit: u64 = 1 << ((63 - v.leading_zeros()) & !1);
    while bit != 0 {
        if rem >= res + bit {
            rem -= res + bit;
            res = (res >> 1) + bit;
        } else {
            res >>= 1;
        }
        bit >>= 2;
    }
    res
}

/// |(x, y)| of two Q<F> values, in Q<F>.
pub fn hypot<const F: i32>(x: Q<F>, y: Q<F>) -> Q<F> {
    let s = (x.0 as i64 * x.0 as i64) as u64 + (y.0 as i64 * y.0 as i64) as u64;
    let r = isqrt(s);
    Q(if r > i32::MAX as u64 { i32::MAX } else { r as i32 })
}

/// `(|(x, y)|, 1 / |(x, y)|)` for Q22 lengths, the reciprocal in Q26 of 1/mm (lengths down
/// to 1/32 mm); `None` at 0 or past the formats. Newton on the inverse square root (products only, no division):
/// `y <- y (3 - v y^2) / 2` from a two-piece start, four steps (relative 1e-9).
pub fn hypot_inv(x: Q<22>, y: Q<22>) -> Option<(Q<22>, Q<26>)> {
    let s = (x.0 as i64 * x.0 as i64) as u64 + (y.0 as i64 * y.0 as i64) as u64; // Q44 mm^2
    if s == 0 {
        return None;
    }
    // s 2^l = v 2^62 with v in [1, 4) (l even); z = v at Q30
    let l = (s.leading_zeros() & !1) as i32;
    let z = (s << l) >> 32;
    let mul = |a: u64, b: u64| (a * b + (1 << 29)) >> 30;
    let three = 3u64 << 30;
    let mut r: u64 = if z < (2u64 << 30) { 912680550 } else { 644245094 }; // 0.85, 0.6
    for _ in 0..4 {
        r = mul(r, three.saturating_sub(mul(z, mul(r, r)))) >> 1;
    }
    let sqrt_v = mul(z, r); // Q30, in [1, 2)
                            // |(x, y)|^2 = s 2^-44 = v 2^(18 - l): |.| = sqrt(v) 2^((18 - l) / 2), 1/|.| = r 2^((l - 18) / 2)
    let h = (18 - l) / 2;
    let span = if 8 - h >= 0 { sqrt_v >> (8 - h) } else { sqrt_v.checked_shl((h - 8) as u32)? };
    let inv = if h + 4 >= 0 { r >> (h + 4) } else { r.checked_shl((-h - 4) as u32)? };
    if span > i32::MAX as u64 || inv > i32::MAX as u64 {
        return None;
    }
    Some((Q(span as i32), Q(inv as i32)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_within_a_few_units_of_q30() {
        let mut worst = 0f64;
        let mut x = -7.9;
        while x < 7.9 {
            let (s, c) = sin_cos(Rad::from_f64(x));
            let xr = Rad::from_f64(x).to_f64();
            worst = worst.max((s.to_f64() - libm::sin(xr)).abs()).max((c.to_f64() - libm::cos(xr)).abs());
            x += 0.000731;
        }
        assert!(worst < 5e-9, "{worst}");
    }

    #[test]
    fn isqrt_is_the_floor() {
        for v in [0u64, 1, 2, 3, 4, 15, 16, 17, 1 << 40, (1 << 62) + 12345, u64::MAX >> 1] {
            let r = isqrt(v);
            assert!(r * r <= v && (r + 1) * (r + 1) > v, "{v}");
        }
        let h = hypot(Q::<22>::from_f64(3.0), Q::<22>::from_f64(4.0));
        assert!((h.to_f64() - 5.0).abs() < 1e-6);
        for (x, y) in [(3.0, 4.0), (0.1, 0.0), (2.58, 0.4165), (-40.0, 77.0), (0.03, 0.01), (300.0, 300.0)] {
            let (qx, qy) = (Q::<22>::from_f64(x), Q::<22>::from_f64(y));
            let (s, i) = hypot_inv(qx, qy).unwrap();
            let want = libm::hypot(qx.to_f64(), qy.to_f64());
            assert!((s.to_f64() - want).abs() < 2.4e-7 + 3e-9 * want, "{x} {y}: {} vs {want}", s.to_f64());
            assert!((i.to_f64() - 1.0 / want).abs() < 3e-8 + 2e-9 / want, "{x} {y}: {} vs {}", i.to_f64(), 1.0 / want);
        }
        assert_eq!(hypot_inv(Q(0), Q(0)), None);
        assert_eq!(hypot_inv(Q::<22>::from_f64(1e-3), Q(0)), None);
    }
}
