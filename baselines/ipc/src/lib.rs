//! Mesh-based Incremental Potential Contact (Li et al. 2020, "IPC") for
//! articulated rigid bodies on the SDRS position-level dynamics: the
//! baseline the paper compares SDRS against. Everything except the contact
//! model (and, in co-design, the shape parameterization) is shared with the
//! core, so a comparison differs only there.
//!
//! - [`distance`]: classified unsigned squared distances of point–triangle and
//!   edge–edge stencils (point–point / point–line / point–plane / line–line);
//! - [`barrier`], [`mollifier`], [`primitive`]: IPC's barrier on squared
//!   distances, the parallel-edge mollifier, per-primitive value, gradient
//!   and PSD-projected Hessian;
//! - [`mesh`]: each link's surface as a triangle mesh (the triangulated
//!   surfaces of its convex hulls, or its source mesh: [`surface`]);
//! - [`ccd`]: additive CCD on linear trajectories and the conservative
//!   curved-path bound used by the line search;
//! - [`contact`], [`friction`]: the IPC contact and lagged friction terms
//!   behind the core's `Energy` trait;
//! - [`factory`]: the [`sdrs::scene::ContactModelFactory`] the CLI passes to
//!   `Scene::simulator_with`.

pub mod adjoint;
pub mod adjoint_stencil;
pub mod barrier;
pub mod broad_phase;
pub mod cage;
pub mod ccd;
pub mod contact;
pub mod distance;
pub mod factory;
pub mod friction;
pub mod friction_stencil;
pub mod line_search;
pub mod mesh;
pub mod mollifier;
pub mod pair;
pub mod primitive;
pub mod settings;
pub mod start_check;
pub mod surface;

pub use contact::{IpcContact, IpcParams};
pub use factory::IpcFactory;
