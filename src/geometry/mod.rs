//! Geometry stages shared by contact terms: world-space hull vertices and the
//! broad phase.

pub mod aabb;
pub mod broad_phase;
pub mod hulls;
pub mod parallel;
pub mod sampling;
pub mod topology;

pub use aabb::Aabb;
pub use broad_phase::{BroadPhase, hull_boxes};
pub use hulls::{HullId, HullPose, WorldHulls};
pub use parallel::PairWork;
