#![no_std]
pub mod error;
pub mod params;
pub mod real;
