//! Helpers shared by the unit tests.

use cam_core::DVec3;
use proptest::prelude::*;

/// Points of the cube `[-h, h]³` (mm).
pub(crate) fn v3(h: f64) -> impl Strategy<Value = DVec3> {
    (-h..h, -h..h, -h..h).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// Deterministic pseudo-random numbers in [0, 1).
pub(crate) struct Lcg(pub u64);

impl Lcg {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
