//! `cam-sample`: constant-arc-length sampling of a part's top surface (CyberCut,
//! "Discretization of the surface").
//!
//! The part is cut by parallel vertical planes `v = const` of a [`RasterFrame`] (`u` along the
//! passes, `v` across them). In each plane the **top surface** is the exact upper envelope of
//! the section of the closed triangles ([`Sectioner::top_profile`]): several disjoint
//! [`Profile`]s where the plane leaves the part (holes, open meshes), vertical walls as
//! vertical jumps. Each profile is resampled at constant arc length ([`resample_u`]), so steep
//! stretches get denser `u` than flat ones. [`sample_part`] does it all, in parallel over the
//! planes, deterministically.
//!
//! # Semantics
//! - The section is that of the **closed** triangles: a vertex or edge on the plane belongs
//!   to it, a triangle lying in the plane contributes its edges (its upper edge is on the
//!   envelope), a triangle perpendicular to the plane gives a vertical segment. Shared edges
//!   are crossed in a canonical orientation, so neighbours produce bit-identical points and
//!   no spurious gaps or duplicates appear.
//! - The envelope is exact up to f64 rounding (crossings computed, not sampled). Pieces of
//!   zero length (the plane touching the part in a point, a free-standing vertical fin) are
//!   not reported.
//! - Profiles split only where no triangle covers `u`. Real meshes have cracks (edges that
//!   should be shared but are a fraction of a micron apart); [`bridge_gaps`] joins gaps up to
//!   a given width, and [`sample_part`] bridges those below [`CRACK_GAP_MM`].
//! - Frame: [`RasterFrame`]; `angle_deg = 0` is passes along +X, planes `y = const`.
//!
//! ```
//! use cam_core::{DVec3, Mesh, Triangle};
//! use cam_sample::{RasterFrame, Sectioner, resample_u};
//!
//! // A 10 x 10 mm plane tilted 45° about Y: z = x.
//! let p = |x: f64, y: f64| DVec3::new(x, y, x);
//! let mesh = Mesh::from_triangles(
//!     vec![
//!         Triangle::new(p(0.0, 0.0), p(10.0, 0.0), p(10.0, 10.0)),
//!         Triangle::new(p(0.0, 0.0), p(10.0, 10.0), p(0.0, 10.0)),
//!     ],
//!     "<memory>",
//! )
//! .unwrap();
//! let s = Sectioner::new(&mesh, RasterFrame::new(0.0));
//! let profiles = s.top_profile(5.0);
//! assert_eq!(profiles.len(), 1);
//! let u = resample_u(&profiles[0], 1.0);
//! // Arc step 1 mm on a 45° slope: u steps of cos 45°.
//! assert!((u[1] - u[0] - 0.5f64.sqrt()).abs() < 1e-12);
//! ```

mod envelope;
mod error;
mod frame;
mod part;
mod profile;
mod section;

pub use envelope::{Seg, upper_envelope};
pub use error::SampleError;
pub use frame::RasterFrame;
pub use part::{SampleConfig, Section, plane_positions, sample_part};
pub use profile::{CRACK_GAP_MM, MERGE_U_MM, Profile, bridge_gaps, resample_u, try_resample_u};
pub use section::Sectioner;

/// Upper limit on the number of section planes and on the number of sample points one
/// request may produce (50 million); beyond it [`sample_part`] returns a
/// [`SampleError`] instead of exhausting memory.
pub const MAX_POINTS: usize = 50_000_000;
