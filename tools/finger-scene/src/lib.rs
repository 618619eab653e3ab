//! Scenes (docs/scenes.md): TOML files that say which finger to solve, at which tensions and
//! voltages, with which solver and what to output; run on the model (f64) and written as CSV
//! and SVG postures. One way through the modules, no cycles: `scene` (the format) → `run`
//! (the model) → `csv`, `svg` (the outputs); `reference` plugs the continuum reference in.

pub mod csv;
pub mod drawing;
pub mod reference;
pub mod run;
pub mod scene;
pub mod svg;

pub use csv::{postures_csv, summary_csv};
pub use reference::{continuum_params, reference_solver, ContinuumReference};
pub use run::{posture_points, run, Kind, Posture, RefPosture, ReferenceSolver, SceneResult};
pub use scene::{parse, read_file, Drive, FingerSpec, MatchSpec, OutputSpec, Pos, Reference, Scene, SceneError, SolverSpec};

/// The files a scene writes, by name, with their contents (nothing is written here).
pub fn outputs(r: &SceneResult) -> Vec<(String, String)> {
    let mut files = vec![(format!("{}.csv", r.scene.name), summary_csv(r))];
    if r.scene.output.postures {
        files.push((format!("{}-postures.csv", r.scene.name), postures_csv(r)));
        files.push((format!("{}.svg", r.scene.name), svg::plot(r)));
    }
    files
}

/// Read, parse and run a scene file (`scene::read_file`, then `run`).
pub fn run_file(path: &std::path::Path, reference: Option<&dyn ReferenceSolver>) -> Result<SceneResult, SceneError> {
    run(&read_file(path)?, reference)
}
