//! Calibration (placeholder).
