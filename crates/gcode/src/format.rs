//! Fixed-decimal number formatting shared by the writers.
//!
//! The text is exactly what `format!("{v:.d$}")` prints (the correctly rounded decimal,
//! ties to even on the exact binary value), without its negative zero. A program of
//! 20,000 moves prints some 60,000 numbers, and the standard formatter's exact path
//! (big-number arithmetic for every value with a fixed precision) was a fifth of
//! `cam plan` on a ball cutter; so values that are not near a rounding tie are rounded
//! with one multiplication, and only the rest go through `format!`.

/// Powers of ten up to the largest precision the fast path takes.
const POW10: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

/// Largest scaled magnitude `|v|·10^d` the fast path takes: below it one unit in the last
/// place of the scaled value is at most 2^-22 < 2.4e-7.
const FAST_LIMIT: f64 = 1e9;

/// A scaled value whose fraction lies within this of one half is a possible tie; the
/// product's rounding error (half a unit in the last place, ≤ 1.2e-7 below
/// [`FAST_LIMIT`]) cannot move a value across one half from farther away.
const TIE_MARGIN: f64 = 1e-6;

/// `v` with exactly `decimals` digits after the point; never prints `-0.000`.
pub(crate) fn fixed(v: f64, decimals: usize) -> String {
    if let Some(&p) = POW10.get(decimals) {
        let y = v.abs() * p;
        if y < FAST_LIMIT {
            let fl = y.floor();
            let frac = y - fl;
            if (frac - 0.5).abs() > TIE_MARGIN {
                let n = if frac > 0.5 { fl + 1.0 } else { fl } as u64;
                let mut out = String::with_capacity(decimals + 12);
                push_scaled(&mut out, v < 0.0 && n != 0, n, decimals);
                return out;
            }
        }
    }
    standard(v, decimals)
}

/// The standard formatter's text for `v` at `decimals` digits, without its negative zero:
/// what [`fixed`] prints, the slow way.
fn standard(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// Appends `±n / 10^decimals` with exactly `decimals` digits after the point.
fn push_scaled(out: &mut String, negative: bool, n: u64, decimals: usize) {
    let mut digits = [0u8; 24];
    let mut len = 0;
    let mut m = n;
    // At least one digit before the point.
    while len < decimals + 1 || m > 0 {
        digits[len] = b'0' + (m % 10) as u8;
        m /= 10;
        len += 1;
    }
    if negative {
        out.push('-');
    }
    for i in (0..len).rev() {
        out.push(digits[i] as char);
        if i == decimals && decimals > 0 {
            out.push('.');
        }
    }
}

#[cfg(test)]
mod tests {
    use super::standard as reference;
    use proptest::prelude::*;

    #[test]
    fn no_negative_zero() {
        assert_eq!(super::fixed(-0.00001, 4), "0.0000");
        assert_eq!(super::fixed(-0.00006, 4), "-0.0001");
        assert_eq!(super::fixed(2.5, 1), "2.5");
        assert_eq!(super::fixed(-0.0, 3), "0.000");
        assert_eq!(super::fixed(0.0, 0), "0");
    }

    #[test]
    fn ties_and_edges_match_the_standard_formatter() {
        let cases = [
            0.5,
            1.5,
            2.5,
            -2.5,
            0.125,
            0.375,
            1.00005,
            1.00015,
            2.675,
            1.0005,
            -1.0005,
            5e-5,
            999_999.999_95,
            123.456_75,
            99_999.999_95,
            0.049_999_999_999,
            9.999_95,
            1e9,
            1e12 + 0.5,
            1e300,
            4.503_599_627_370_495_5e15,
            f64::MIN_POSITIVE,
            -1e-320,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
        ];
        for v in cases {
            for d in 0..12 {
                assert_eq!(super::fixed(v, d), reference(v, d), "{v:e} at {d} decimals");
            }
        }
    }

    proptest! {
        #[test]
        fn matches_the_standard_formatter(
            v in prop_oneof![
                -2000.0..2000.0f64,
                -1.0..1.0f64,
                any::<f64>(),
                // Exact ties at four and three decimals, and their neighbours.
                (-20_000_000i64..20_000_000).prop_map(|k| (k as f64 + 0.5) / 1e4),
                (-20_000_000i64..20_000_000).prop_map(|k| (k as f64 + 0.5) / 1e3),
                (-20_000_000i64..20_000_000, -3i64..=3).prop_map(|(k, u)| {
                    let t = (k as f64 + 0.5) / 1e4;
                    f64::from_bits((t.to_bits() as i64 + u) as u64)
                }),
            ],
            d in 0usize..10,
        ) {
            prop_assert_eq!(super::fixed(v, d), reference(v, d));
        }
    }
}
