//! Scene files: read, run on the model (f64), write CSV and SVG postures (docs/scenes.md).
pub mod scene;
pub mod svg;
pub use scene::*;
