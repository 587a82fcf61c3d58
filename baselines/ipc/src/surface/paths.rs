//! Which model links have a `surface_mesh` (robots' links, objects,
//! obstacles), resolved against the scene file's directory.

use sdrs::scene::environment::ENVIRONMENT;
use sdrs::scene::{Invalid, Scene};
use std::path::PathBuf;

/// A link's source mesh: the file and the scene key that names it.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfacePath {
    pub file: PathBuf,
    /// E.g. `robots[0] ("arm").links[2] ("hand").surface_mesh`.
    pub element: String,
}

/// Per model link, its `surface_mesh` (`None` for links without one).
pub fn surface_paths(scene: &Scene) -> Result<Vec<Option<SurfacePath>>, Invalid> {
    let model = &scene.model;
    let dir = scene
        .source
        .parent()
        .map(|d| d.to_path_buf())
        .unwrap_or_default();
    let mut out = vec![None; model.links.len()];
    let mut put = |robot: &str, link: &str, path: &str, element: String| {
        let i = model
            .links
            .iter()
            .position(|l| l.name == link && model.robots[l.robot].name == robot)
            .ok_or_else(|| {
                Invalid::new(&element, format!("no model link {robot}/{link} (internal)"))
            })?;
        if path.trim().is_empty() {
            return Err(Invalid::new(&element, "the path is empty"));
        }
        out[i] = Some(SurfacePath {
            file: dir.join(path),
            element,
        });
        Ok::<(), Invalid>(())
    };
    let spec = &scene.spec;
    for (i, r) in spec.robots.iter().enumerate() {
        for (j, l) in r.links.iter().enumerate() {
            if let Some(p) = &l.surface_mesh {
                let el = format!(
                    "robots[{i}] (\"{}\").links[{j}] (\"{}\").surface_mesh",
                    r.name, l.name
                );
                put(&r.name, &l.name, p, el)?;
            }
        }
    }
    for (i, o) in spec.objects.iter().enumerate() {
        if let Some(p) = &o.surface_mesh {
            let el = format!("objects[{i}] (\"{}\").surface_mesh", o.name);
            put(&o.name, &o.name, p, el)?;
        }
    }
    for (i, o) in spec.obstacles.iter().enumerate() {
        if let Some(p) = &o.surface_mesh {
            let el = format!("obstacles[{i}] (\"{}\").surface_mesh", o.name);
            put(ENVIRONMENT, &o.name, p, el)?;
        }
    }
    Ok(out)
}
