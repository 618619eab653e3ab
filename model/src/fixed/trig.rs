//! sin and cos of a [`Rad`] (Q28) angle in [`Unit`] (Q30): reduction by the nearest multiple
//! of pi/2, then Taylor polynomials on [-pi/4, pi/4] (degree 9 / 10, Horner, 64-bit products;
//! truncation below 2e-9); the square root of a 64-bit value.
use super::q::{Q, Rad, Unit};

const FRAC_2_PI_Q30: i64 = 683565276; // 2/pi 2^30
const PI_2_Q30: i64 = 1686629713; // pi/2 2^30, truncated
const PI_2_LO_Q60: i64 = 70064198; // the rest of pi/2 below 2^-30, at Q60

/// `(sin x, cos x)`; any |x| < 8 rad (the format's range).
pub fn sin_cos(x: Rad) -> (Unit, Unit) {
    // k = round(x 2/pi); r = x - k pi/2 at Q30
    let xq = x.0 as i64; // Q28
    let k = ((xq * FRAC_2_PI_Q30) + (1i64 << 57)) >> 58;
    let r = (xq << 2) - k * PI_2_Q30 - (k * PI_2_LO_Q60 >> 30); // Q30, |r| <= pi/4
    let u = (r * r) >> 30; // r^2, Q30
    let mul = |a: i64, b: i64| (a * b + (1 << 29)) >> 30;
    // sin r = r (1 - u/6 (1 - u/20 (1 - u/42 (1 - u/72))))
    const S: [i64; 4] = [178956971, 53687091, 25565282, 14913081]; // 2^30 / 6, 20, 42, 72
    let mut s = (1i64 << 30) - mul(u, S[3]);
    s = (1i64 << 30) - mul(mul(u, S[2]), s);
    s = (1i64 << 30) - mul(mul(u, S[1]), s);
    s = (1i64 << 30) - mul(mul(u, S[0]), s);
    let s = mul(r, s);
    // cos r = 1 - u/2 (1 - u/12 (1 - u/30 (1 - u/56 (1 - u/90))))
    const C: [i64; 5] = [536870912, 89478485, 35791394, 19173961, 11930465]; // 2^30 / 2, 12, 30, 56, 90
    let mut c = (1i64 << 30) - mul(u, C[4]);
    c = (1i64 << 30) - mul(mul(u, C[3]), c);
    c = (1i64 << 30) - mul(mul(u, C[2]), c);
    c = (1i64 << 30) - mul(mul(u, C[1]), c);
    c = (1i64 << 30) - mul(mul(u, C[0]), c);
    let (s, c) = (Q(s as i32), Q(c as i32));
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
    let mut bit: u64 = 1 << 62;
    while bit > v {
        bit >>= 2;
    }
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
    }
}
