//! Fixed-decimal number formatting shared by the writers.

/// `v` with exactly `decimals` digits after the point; never prints `-0.000`.
pub(crate) fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn no_negative_zero() {
        assert_eq!(super::fixed(-0.00001, 4), "0.0000");
        assert_eq!(super::fixed(-0.00006, 4), "-0.0001");
        assert_eq!(super::fixed(2.5, 1), "2.5");
    }
}
