//! Active contact pairs and their separating planes along a recorded run,
//! for viewers (`sdrs simulate --export DIR --planes` → `DIR/contacts.csv`).
//!
//! The planes are recomputed from the recorded link poses after the run,
//! with the scene's barrier width `s`: per step, the broad phase lists hull
//! pairs on different, non-excluded links within `2s/(1−s)`, and the
//! optimal plane `p* = (n*, o*) = argmin_p U*(p)` of each pair is solved
//! cold (no warm start). The simulation itself is untouched, so recording
//! planes cannot change a trajectory. `U*` is strictly convex in `p`, so the
//! plane is the one the simulator's contact term used at that state (up to
//! the inner solver's tolerance).
//!
//! The recorded plane is normalised: unit normal `n̂ = n*/‖n*‖` (world
//! frame, pointing from hull `a` to hull `b`) and offset `d = o*/‖n*‖` (m),
//! so `n̂·X + d` is the signed distance of a world point `X` from the plane:
//! negative on hull `a`'s side, positive on hull `b`'s.

use crate::contact::{self, ContactParams, ContactScratch, PairOutcome};
use crate::geometry::{BroadPhase, WorldHulls};
use crate::math::Pose;
use crate::model::Model;
use std::collections::BTreeSet;

/// One active pair at one recorded step.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactRecord {
    /// Index of the recorded state (0 = initial).
    pub step: usize,
    /// `(link, hull within the link)` of hull `a` (negative side).
    pub a: (usize, usize),
    /// `(link, hull within the link)` of hull `b` (positive side).
    pub b: (usize, usize),
    /// Unit plane normal `n̂` (world).
    pub normal: [f64; 3],
    /// Plane offset `d` (m): the plane is `n̂·X + d = 0`.
    pub offset: f64,
    /// GJK distance between the hulls (m).
    pub distance: f64,
}

/// A plane solve failed at a recorded state (it succeeded during the run,
/// so this means the recorded poses were altered).
#[derive(Debug, thiserror::Error)]
#[error("step {step}: links {a} and {b}: {msg}")]
pub struct ContactsError {
    pub step: usize,
    pub a: String,
    pub b: String,
    pub msg: String,
}

/// Active pairs and planes at every recorded state `poses[k]` (see the
/// module docs). `s` is the barrier width, `excluded` the link pairs
/// `(i, j)`, `i < j`, that never interact.
pub fn active_contacts(
    model: &Model,
    s: f64,
    excluded: &BTreeSet<(usize, usize)>,
    poses: &[Vec<Pose>],
) -> Result<Vec<ContactRecord>, ContactsError> {
    let params = ContactParams::with_width(s);
    let mut hulls = WorldHulls::new(model);
    let mut broad = BroadPhase::default();
    let mut pairs = Vec::new();
    let mut scratch = ContactScratch::new();
    let mut out = Vec::new();
    let name = |l: usize| {
        format!(
            "{}/{}",
            model.robots[model.links[l].robot].name, model.links[l].name
        )
    };
    for (step, pose) in poses.iter().enumerate() {
        hulls.update(model, pose);
        broad.candidate_pairs(&hulls, params.support_distance(), excluded, &mut pairs);
        for &(ha, hb) in &pairs {
            let (ia, ib) = (hulls.ids[ha], hulls.ids[hb]);
            let err = |msg: String| ContactsError {
                step,
                a: name(ia.link),
                b: name(ib.link),
                msg,
            };
            let res = contact::contact_pair(
                hulls.hull_pose(model, pose, ha),
                hulls.hull_pose(model, pose, hb),
                &params,
                None,
                contact::Need::Value,
                &mut scratch,
            )
            .map_err(|e| err(e.to_string()))?;
            match res {
                PairOutcome::OutOfRange { .. } => {}
                PairOutcome::Intersecting => {
                    return Err(err("the hulls intersect".into()));
                }
                PairOutcome::Separated(c) => {
                    let n = c.plane.fixed_rows::<3>(0).into_owned();
                    let len = n.norm();
                    out.push(ContactRecord {
                        step,
                        a: (ia.link, ia.hull),
                        b: (ib.link, ib.hull),
                        normal: (n / len).into(),
                        offset: c.plane[3] / len,
                        distance: c.distance,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// `contacts.csv`: `step,link_a,hull_a,link_b,hull_b,nx,ny,nz,d,distance`
/// (shortest round-trip numbers; see [`ContactRecord`]).
pub fn contacts_csv(records: &[ContactRecord]) -> String {
    let mut s = String::from("step,link_a,hull_a,link_b,hull_b,nx,ny,nz,d,distance\n");
    for r in records {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{}\n",
            r.step,
            r.a.0,
            r.a.1,
            r.b.0,
            r.b.1,
            r.normal[0],
            r.normal[1],
            r.normal[2],
            r.offset,
            r.distance
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::transform_point;

    /// Box on the ground after a short drop: the recorded planes separate
    /// the pair (every vertex of `a` on the negative side, of `b` on the
    /// positive one), and pairs appear once the box is within range.
    #[test]
    fn planes_separate_the_recorded_pairs() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/box_on_ground.yaml");
        let scene = crate::scene::Scene::load(&path).unwrap();
        let mut sim = scene.simulator();
        let traj = crate::sim::run::run_recording(&mut sim, 200, true, |_| {}).unwrap();
        let c = scene.contact.as_ref().unwrap();
        let recs = active_contacts(&scene.model, c.s, &c.excluded, &traj.poses).unwrap();
        assert!(!recs.is_empty(), "the box never came within range");
        for r in &recs {
            let n = nalgebra::Vector3::from(r.normal);
            assert!((n.norm() - 1.0).abs() < 1e-12);
            let side = |(l, h): (usize, usize)| {
                let a = &traj.poses[r.step][l];
                scene.model.links[l].hulls[h]
                    .x_local
                    .iter()
                    .map(|x| n.dot(&transform_point(a, x)) + r.offset)
                    .collect::<Vec<_>>()
            };
            assert!(side(r.a).iter().all(|&y| y < 0.0), "{r:?}");
            assert!(side(r.b).iter().all(|&y| y > 0.0), "{r:?}");
            // The plane lies within the gap: its distances to both hulls sum to the gap.
            let (da, db) = (
                side(r.a).iter().fold(f64::INFINITY, |m, y| m.min(-y)),
                side(r.b).iter().fold(f64::INFINITY, |m, y| m.min(*y)),
            );
            assert!(
                da + db <= r.distance * (1.0 + 1e-6) + 1e-12,
                "{r:?} {da} {db}"
            );
        }
        let csv = contacts_csv(&recs);
        assert_eq!(csv.lines().count(), recs.len() + 1);
    }
}
