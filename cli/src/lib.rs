//! The parts of the `sdrs` application that the Python package shares
//! (`sdrs-py` depends on this library): the SVG plots ([`svg`]) and
//! `calibrated.xml` ([`calibrated_mjcf`]). The command
//! line itself is the `sdrs` binary (`main.rs`).

pub mod calibrated_mjcf;
pub mod svg;
