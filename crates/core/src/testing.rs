//! Test helpers shared by the workspace.

/// Asserts `|a - b| <= tol`, printing both values and the difference.
///
/// ```
/// cam_core::assert_near!(1.0, 1.0 + 1e-12, 1e-9);
/// ```
#[macro_export]
macro_rules! assert_near {
    ($a:expr, $b:expr, $tol:expr $(,)?) => {{
        let (a, b, tol): (f64, f64, f64) = ($a, $b, $tol);
        assert!(
            (a - b).abs() <= tol,
            "assert_near failed: {} = {a}, {} = {b}, |diff| = {:e} > {tol:e}",
            stringify!($a),
            stringify!($b),
            (a - b).abs()
        );
    }};
    ($a:expr, $b:expr, $tol:expr, $($msg:tt)+) => {{
        let (a, b, tol): (f64, f64, f64) = ($a, $b, $tol);
        assert!(
            (a - b).abs() <= tol,
            "assert_near failed: {a} vs {b}, |diff| = {:e} > {tol:e}: {}",
            (a - b).abs(),
            format!($($msg)+)
        );
    }};
}
