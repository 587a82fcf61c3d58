//! A recorded run as viewers need it: every link's hulls (link frame), the
//! link poses at every recorded time and, optionally, the active contact
//! pairs with their separating planes. Built from a run in memory
//! ([`Playback::from_run`]) or read back from `sdrs simulate --export DIR`
//! ([`Playback::load_export`]: `hulls.json`, `poses.csv`, and
//! `contacts.csv` when the run was exported with `--planes`).

use super::contacts::ContactRecord;
use super::{HullExport, LinkExport, Trajectory};
use crate::math::Pose;
use crate::model::Model;
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use std::path::{Path, PathBuf};

/// Problems reading an exported run.
#[derive(Debug, thiserror::Error)]
pub enum PlaybackError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: line {line}: {msg}", path.display())]
    Parse {
        path: PathBuf,
        line: usize,
        msg: String,
    },
}

/// See the module docs.
#[derive(Clone, Debug)]
pub struct Playback {
    pub links: Vec<LinkExport>,
    /// Recorded times (s), increasing.
    pub times: Vec<f64>,
    /// `poses[k][link]`: world pose `[R | t]` of each link at `times[k]`.
    pub poses: Vec<Vec<Pose>>,
    /// Active pairs and planes (empty when not recorded).
    pub contacts: Vec<ContactRecord>,
}

/// A convex hull as a triangle mesh: vertices (link frame, m) and
/// counter-clockwise triangles seen from outside.
pub type HullMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// The convex hull of a vertex cloud as a triangle mesh (parry3d's
/// quickhull; fewer than 4 points give an empty mesh).
pub fn hull_mesh(points: &[[f64; 3]]) -> HullMesh {
    if points.len() < 4 {
        return (Vec::new(), Vec::new());
    }
    let cloud: Vec<_> = points
        .iter()
        .map(|p| parry3d_f64::math::Vector::new(p[0], p[1], p[2]))
        .collect();
    let (v, t) = parry3d_f64::transformation::convex_hull(&cloud);
    (v.iter().map(|p| [p.x, p.y, p.z]).collect(), t)
}

/// The translation and unit quaternion `(x, y, z, w)` of a rigid pose.
pub fn pose_trs(a: &Pose) -> ([f64; 3], [f64; 4]) {
    let r = Rotation3::from_matrix_unchecked(crate::math::rot(a));
    let q = UnitQuaternion::from_rotation_matrix(&r);
    let t = a.column(3);
    ([t[0], t[1], t[2]], [q.i, q.j, q.k, q.w])
}

impl Playback {
    /// From a run recorded with poses (`run_recording(…, poses = true, …)`).
    pub fn from_run(model: &Model, traj: &Trajectory, contacts: Vec<ContactRecord>) -> Self {
        Playback {
            links: HullExport::new(model, []).links,
            times: traj.times.clone(),
            poses: traj.poses.clone(),
            contacts,
        }
    }

    /// Reads `dir/hulls.json`, `dir/poses.csv` and (if present)
    /// `dir/contacts.csv`, checking that every row names a known link,
    /// steps are contiguous and every number is finite.
    pub fn load_export(dir: &Path) -> Result<Self, PlaybackError> {
        let read = |name: &str| {
            let path = dir.join(name);
            std::fs::read_to_string(&path)
                .map(|s| (s, path.clone()))
                .map_err(|source| PlaybackError::Io { path, source })
        };
        let (text, path) = read("hulls.json")?;
        let hulls: HullExport = serde_json::from_str(&text).map_err(|e| PlaybackError::Parse {
            path: path.clone(),
            line: e.line(),
            msg: e.to_string(),
        })?;
        let n = hulls.links.len();
        let (text, path) = read("poses.csv")?;
        let (times, poses) = parse_poses(&text, n, &path)?;
        let cpath = dir.join("contacts.csv");
        let contacts = if cpath.exists() {
            let (text, path) = read("contacts.csv")?;
            parse_contacts(&text, &hulls.links, poses.len(), &path)?
        } else {
            Vec::new()
        };
        Ok(Playback {
            links: hulls.links,
            times,
            poses,
            contacts,
        })
    }

    /// Duration of the recording (s).
    pub fn duration(&self) -> f64 {
        match (self.times.first(), self.times.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }
}

fn numbers(
    fields: &[&str],
    path: &Path,
    line: usize,
    what: &str,
) -> Result<Vec<f64>, PlaybackError> {
    fields
        .iter()
        .map(|f| match f.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(PlaybackError::Parse {
                path: path.into(),
                line,
                msg: format!("{what}: `{f}` is not a finite number"),
            }),
        })
        .collect()
}

/// The data rows of a CSV export: `(line number, fields)`, each row checked
/// to hold `fields` fields.
fn csv_rows<'a>(
    text: &'a str,
    fields: usize,
    path: &'a Path,
) -> impl Iterator<Item = Result<(usize, Vec<&'a str>), PlaybackError>> + 'a {
    text.lines().enumerate().skip(1).map(move |(i, l)| {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() != fields {
            return Err(parse_error(
                path,
                i + 1,
                format!("{} fields, expected {fields}", f.len()),
            ));
        }
        Ok((i + 1, f))
    })
}

fn parse_error(path: &Path, line: usize, msg: String) -> PlaybackError {
    PlaybackError::Parse {
        path: path.into(),
        line,
        msg,
    }
}

/// `poses.csv` → times and per-step poses of `n` links.
fn parse_poses(
    text: &str,
    n: usize,
    path: &Path,
) -> Result<(Vec<f64>, Vec<Vec<Pose>>), PlaybackError> {
    let (mut times, mut poses) = (Vec::new(), Vec::<Vec<Pose>>::new());
    for row in csv_rows(text, 16, path) {
        let (line, f) = row?;
        let err = |msg: String| parse_error(path, line, msg);
        let step: usize = f[0]
            .parse()
            .map_err(|_| err(format!("step `{}` is not an index", f[0])))?;
        let link: usize = f[2]
            .parse()
            .map_err(|_| err(format!("link `{}` is not an index", f[2])))?;
        let x = numbers(&[&[f[1]][..], &f[4..]].concat(), path, line, "pose")?;
        if link >= n {
            return Err(err(format!(
                "link {link} does not exist (hulls.json has {n})"
            )));
        }
        if step == poses.len() && link == 0 {
            times.push(x[0]);
            poses.push(Vec::with_capacity(n));
        }
        if step + 1 != poses.len() || link != poses[step].len() {
            return Err(err(format!(
                "expected step {} link {}, found step {step} link {link}",
                poses.len().saturating_sub(1),
                poses.last().map_or(0, |p| p.len())
            )));
        }
        poses[step].push(Pose::from_column_slice(&x[1..]));
    }
    if let Some(last) = poses.last().filter(|p| p.len() != n) {
        return Err(parse_error(
            path,
            text.lines().count(),
            format!("the last step has {} of {n} links", last.len()),
        ));
    }
    Ok((times, poses))
}

/// `contacts.csv` (see [`super::contacts::contacts_csv`]).
fn parse_contacts(
    text: &str,
    links: &[LinkExport],
    steps: usize,
    path: &Path,
) -> Result<Vec<ContactRecord>, PlaybackError> {
    let mut out = Vec::new();
    for row in csv_rows(text, 10, path) {
        let (line, f) = row?;
        let err = |msg: String| parse_error(path, line, msg);
        let idx: Vec<usize> = f[..5]
            .iter()
            .map(|x| x.parse().map_err(|_| err(format!("`{x}` is not an index"))))
            .collect::<Result<_, _>>()?;
        let hull_ok = |l: usize, h: usize| links.get(l).is_some_and(|x| h < x.hulls.len());
        if idx[0] >= steps || !hull_ok(idx[1], idx[2]) || !hull_ok(idx[3], idx[4]) {
            return Err(err(format!(
                "step {} / hull ({}, {}) / hull ({}, {}) out of range",
                idx[0], idx[1], idx[2], idx[3], idx[4]
            )));
        }
        let x = numbers(&f[5..], path, line, "plane")?;
        out.push(ContactRecord {
            step: idx[0],
            a: (idx[1], idx[2]),
            b: (idx[3], idx[4]),
            normal: [x[0], x[1], x[2]],
            offset: x[3],
            distance: x[4],
        });
    }
    Ok(out)
}

/// Centroid of a vertex cloud (m; zero for an empty one).
pub fn centroid(points: &[[f64; 3]]) -> Vector3<f64> {
    let s: Vector3<f64> = points.iter().map(|p| Vector3::from(*p)).sum();
    s / (points.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Export → load round trip is exact (shortest round-trip numbers) and
    /// a corrupted file is an error naming file and line.
    #[test]
    fn export_round_trip_and_errors() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/box_on_ground.yaml");
        let scene = crate::scene::Scene::load(&path).unwrap();
        let mut sim = scene.simulator();
        let traj = crate::sim::run::run_recording(&mut sim, 20, true, |_| {}).unwrap();
        let dir = std::env::temp_dir().join(format!("sdrs_playback_{}", std::process::id()));
        crate::output::export_run(&dir, &scene.model, [], &traj).unwrap();
        let p = Playback::load_export(&dir).unwrap();
        assert_eq!(p.times, traj.times);
        assert_eq!(p.poses, traj.poses);
        assert_eq!(p.links.len(), scene.model.links.len());
        assert!((p.duration() - 20.0 * scene.settings.dt).abs() < 1e-12);
        let csv = std::fs::read_to_string(dir.join("poses.csv")).unwrap();
        std::fs::write(dir.join("poses.csv"), csv.replacen(",0,", ",x,", 2)).unwrap();
        let e = Playback::load_export(&dir).unwrap_err().to_string();
        assert!(e.contains("poses.csv: line 2"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn trs_of_a_rotation_about_z() {
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7);
        let mut a = Pose::zeros();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(r.matrix());
        a.set_column(3, &Vector3::new(1.0, 2.0, 3.0));
        let (t, q) = pose_trs(&a);
        assert_eq!(t, [1.0, 2.0, 3.0]);
        let h = 0.35f64;
        for (x, y) in q.iter().zip([0.0, 0.0, h.sin(), h.cos()]) {
            assert!((x - y).abs() < 1e-15, "{q:?}");
        }
    }
}
