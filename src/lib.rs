//! SDRS — shape-differentiable robot simulation.
//!
//! Pipeline stages, one folder each: [`scene`] (files → model), [`model`]
//! (links, hulls, joints), [`kinematics`] (poses and derivatives), [`energy`]
//! (terms of the step objective), [`sim`] (Newton per step), [`control`]
//! (target signals), [`output`] (trajectory CSV, summary JSON), [`import`]
//! (URDF / OBJ / STL → convex-hull design spaces).
//!
//! The method is the SDRS paper (`shared/paper/sdrs-paper.tex`).

pub mod control;
pub mod energy;
pub mod import;
pub mod kinematics;
pub mod math;
pub mod model;
pub mod scene;
pub mod sim;
