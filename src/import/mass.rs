//! Link masses.
//!
//! - `urdf` (default): the link's `<inertial><mass>` (plus the masses of
//!   geometry-less links merged into it). Links with no positive mass in the
//!   input (bare meshes, `world`-like links, massless URDF links) fall back to
//!   `density × volume`, and the report says so.
//! - `density`: `density × volume` for every link.
//!
//! `volume` is the volume of the union of the link's hulls (estimated on a
//! grid, see [`super::report::union_volume`]). The mass is written as the
//! link's `mass:` in the scene, which the model divides equally over all the
//! link's hull vertices (the paper's `ρ_ij(x) = Σ_m ρ δ(x − x^m)`).

use serde::{Deserialize, Serialize};

/// How masses are assigned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum MassMode {
    Urdf,
    Density,
}

/// Where a link's mass came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MassSource {
    Urdf,
    Density,
    /// `urdf` was asked but the input has no positive mass for the link.
    DensityFallback,
}

/// Mass of a link (kg) and its source.
pub fn link_mass(
    mode: MassMode,
    input_mass: Option<f64>,
    density: f64,
    volume: f64,
) -> (f64, MassSource) {
    let by_volume = (density * volume).max(f64::MIN_POSITIVE);
    match (mode, input_mass) {
        (MassMode::Urdf, Some(m)) if m > 0.0 && m.is_finite() => (m, MassSource::Urdf),
        (MassMode::Urdf, _) => (by_volume, MassSource::DensityFallback),
        (MassMode::Density, _) => (by_volume, MassSource::Density),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_and_fallback() {
        assert_eq!(
            link_mass(MassMode::Urdf, Some(2.0), 1000.0, 1e-3),
            (2.0, MassSource::Urdf)
        );
        assert_eq!(
            link_mass(MassMode::Urdf, None, 1000.0, 1e-3),
            (1.0, MassSource::DensityFallback)
        );
        assert_eq!(
            link_mass(MassMode::Density, Some(2.0), 500.0, 1e-3),
            (0.5, MassSource::Density)
        );
    }
}
