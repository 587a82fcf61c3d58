//! Link masses of an imported robot, as scene mass models
//! ([`crate::model::mass`]).
//!
//! - `urdf` (default): the link's URDF `<inertial>` (origin, mass, full
//!   inertia tensor; geometry-less links merged into it add theirs, moved
//!   into its frame) as a `given` inertial. Links with no positive mass in
//!   the input (bare meshes, `world`-like links, massless URDF links) or
//!   with a non-physical inertia tensor fall back to `solid` hulls at the
//!   default density, and the report says so.
//! - `density`: every link `solid` at the given density (mass, COM and
//!   inertia of the hulls as uniform solids, following the hulls in design
//!   optimization; overlapping hulls superposed).
//!
//! The report lists, per link, the input inertial and the hulls' (as
//! uniform solids scaled to the link's mass, so COM and principal moments
//! compare directly).

use crate::model::Inertial;
use crate::model::mass::{solid_second_moment, solid_triangles};
use crate::scene::schema::MassModelSpec;
use nalgebra::{Matrix4, Vector3};
use serde::{Deserialize, Serialize};

/// How masses are assigned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassMode {
    Urdf,
    Density,
}

impl std::str::FromStr for MassMode {
    type Err = String;
    /// `urdf` or `density` (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        super::pick_name(s, &[MassMode::Urdf, MassMode::Density], |m| match m {
            MassMode::Urdf => "urdf",
            MassMode::Density => "density",
        })
    }
}

/// Where a link's mass came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MassSource {
    Urdf,
    Density,
    /// `urdf` was asked but the input has no usable inertial for the link.
    DensityFallback,
}

/// Mass (kg), centre of mass (m, link frame) and principal moments of
/// inertia about the centre of mass (kg m², ascending).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InertialReport {
    pub mass: f64,
    pub com: [f64; 3],
    pub principal_moments: [f64; 3],
}

impl InertialReport {
    pub fn of(i: &Inertial) -> InertialReport {
        let mut e: Vec<f64> = i.inertia.symmetric_eigenvalues().iter().copied().collect();
        e.sort_by(f64::total_cmp);
        InertialReport {
            mass: i.mass,
            com: i.com.into(),
            principal_moments: [e[0], e[1], e[2]],
        }
    }
}

/// A link's mass model and what the report says about it.
#[derive(Clone, Debug)]
pub struct LinkMass {
    /// The link's mass in the scene (kg).
    pub mass: f64,
    pub source: MassSource,
    /// Written as the link's `mass_model`.
    pub spec: MassModelSpec,
    /// The input's inertial (merged links included), if any.
    pub input: Option<InertialReport>,
    /// The hulls as uniform solids at the link's mass.
    pub hulls: InertialReport,
    /// Why `urdf` fell back to density, if it did.
    pub fallback: Option<String>,
}

impl LinkMass {
    /// `given` or `solid`.
    pub fn model_name(&self) -> &'static str {
        match self.spec {
            MassModelSpec::Given { .. } => "given",
            MassModelSpec::Solid { .. } => "solid",
            MassModelSpec::Vertices => "vertices",
        }
    }
}

/// A massless frame (MJCF joint frames and massless bodies): `given` with
/// mass, centre of mass and inertia zero, whatever the mass mode.
pub fn massless_frame() -> LinkMass {
    let zero = InertialReport {
        mass: 0.0,
        com: [0.0; 3],
        principal_moments: [0.0; 3],
    };
    LinkMass {
        mass: 0.0,
        source: MassSource::Urdf,
        spec: MassModelSpec::Given {
            mass: 0.0,
            com: [0.0; 3],
            inertia: [0.0; 6],
        },
        input: Some(zero.clone()),
        hulls: zero,
        fallback: None,
    }
}

/// The mass model of a link with input second moment `moment` (link frame)
/// and final hulls `hulls` (link frame). Errors: a hull without volume.
pub fn link_mass_model(
    mode: MassMode,
    moment: Option<&Matrix4<f64>>,
    density: f64,
    hulls: &[&[Vector3<f64>]],
) -> Result<LinkMass, String> {
    let mut unit = Matrix4::zeros();
    for (k, h) in hulls.iter().enumerate() {
        let tris = solid_triangles(h).map_err(|e| format!("hull {k}: {e}"))?;
        unit += solid_second_moment(h, &tris, 1.0);
    }
    let volume = unit[(3, 3)];
    let input = moment.map(Inertial::from_second_moment);
    let hulls_at =
        |mass: f64| InertialReport::of(&Inertial::from_second_moment(&(unit * (mass / volume))));
    let solid = |source: MassSource, fallback: Option<String>| LinkMass {
        mass: density * volume,
        source,
        spec: MassModelSpec::Solid {
            density: Some(density),
        },
        input: input.as_ref().map(InertialReport::of),
        hulls: hulls_at(density * volume),
        fallback,
    };
    match (mode, &input) {
        (MassMode::Density, _) => Ok(solid(MassSource::Density, None)),
        (MassMode::Urdf, None) => Ok(solid(
            MassSource::DensityFallback,
            Some("no mass in the input".into()),
        )),
        (MassMode::Urdf, Some(i)) => match i.check() {
            Err(e) => Ok(solid(
                MassSource::DensityFallback,
                Some(format!("the input inertial is not physical ({e})")),
            )),
            Ok(()) => {
                let t = &i.inertia;
                Ok(LinkMass {
                    mass: i.mass,
                    source: MassSource::Urdf,
                    spec: MassModelSpec::Given {
                        mass: i.mass,
                        com: i.com.into(),
                        inertia: [
                            t[(0, 0)],
                            t[(0, 1)],
                            t[(0, 2)],
                            t[(1, 1)],
                            t[(1, 2)],
                            t[(2, 2)],
                        ],
                    },
                    input: Some(InertialReport::of(i)),
                    hulls: hulls_at(i.mass),
                    fallback: None,
                })
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Hull;
    use nalgebra::Matrix3;

    #[test]
    fn modes_and_fallback() {
        let cube = Hull::cuboid(Vector3::repeat(0.1), Vector3::new(0.05, 0.0, 0.0));
        let hulls = [cube.as_slice()];
        let given = Inertial {
            mass: 2.0,
            com: Vector3::new(0.0, 0.01, 0.0),
            inertia: Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.025)),
        };
        let m = given.second_moment();
        let l = link_mass_model(MassMode::Urdf, Some(&m), 1000.0, &hulls).unwrap();
        assert_eq!(
            (l.mass, l.source, l.model_name()),
            (2.0, MassSource::Urdf, "given")
        );
        let inp = l.input.unwrap();
        assert!((inp.principal_moments[2] - 0.025).abs() < 1e-15);
        // The hulls at the link's mass: a 0.1 m cube of 2 kg at x = 0.05.
        assert!((l.hulls.com[0] - 0.05).abs() < 1e-15);
        assert!((l.hulls.principal_moments[0] - 2.0 * 0.02 / 12.0).abs() < 1e-15);
        let l = link_mass_model(MassMode::Urdf, None, 1000.0, &hulls).unwrap();
        assert_eq!(
            (l.source, l.model_name()),
            (MassSource::DensityFallback, "solid")
        );
        assert!((l.mass - 1.0).abs() < 1e-12);
        let l = link_mass_model(MassMode::Density, Some(&m), 500.0, &hulls).unwrap();
        assert_eq!(l.source, MassSource::Density);
        assert!((l.mass - 0.5).abs() < 1e-12);
        let bad = Inertial {
            inertia: Matrix3::from_diagonal(&Vector3::new(1.0, 0.1, 0.1)),
            ..given
        };
        let l =
            link_mass_model(MassMode::Urdf, Some(&bad.second_moment()), 1000.0, &hulls).unwrap();
        assert!(l.fallback.unwrap().contains("triangle"));
    }
}
