//! Cases shared by the model's own tests (model/tests, a dev-dependency of finger-model) and
//! host-tests' soak example: not part of the model, never in the firmware.
//! - [`paper`]: the paper's comparison (section III-B), the matching tension.
//! - [`domain`]: the documented domain's cases, one function per property.
//! - [`material`]: random voltage histories through the film's guard.

pub mod domain;
pub mod material;
pub mod paper;
