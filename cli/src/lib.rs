//! The parts of the `sdrs` application that the Python package shares
//! (`sdrs-py` depends on this library): the SVG plots ([`svg`]), the HTML
//! report pages ([`html`], calibration's [`calibration_report`]),
//! `calibrated.xml` ([`calibrated_mjcf`]), and what the binary shares with
//! its examples: the contact-potential benchmark ([`potential_bench`],
//! `sdrs compare` and `examples/bench_potential.rs`). The command line
//! itself is the `sdrs` binary (`main.rs`).

pub mod calibrated_mjcf;
pub mod calibration_report;
pub mod html;
pub mod potential_bench;
pub mod svg;
