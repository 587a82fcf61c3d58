//! Writing an import's outputs: the design YAML, `<stem>_meshes/<link>.obj`
//! (each hull as one OBJ object, for viewing), `<stem>_meshes/<link>.source.obj`
//! (the link's source meshes in its frame, named by the link's
//! `surface_mesh`: the IPC baseline's `contact.ipc.surface: source`) and the
//! JSON report.
//!
//! Safety rules: an existing output is never replaced without `force`; the
//! input is never written (nor a directory containing it removed); every
//! output is first written to a temporary sibling and renamed into place at
//! the end, and the temporaries are removed on any error, so a failed import
//! leaves nothing behind.

use super::Imported;
use super::error::ImportError;
use super::polytope::convex_hull;
use std::path::{Path, PathBuf};

/// Where the outputs go.
#[derive(Clone, Debug)]
pub struct OutputPaths {
    pub design: PathBuf,
    pub meshes: PathBuf,
    pub report: Option<PathBuf>,
}

impl OutputPaths {
    /// `out` and `<out dir>/<out stem>_meshes/`, plus the report if asked.
    pub fn new(out: &Path, report: Option<&Path>) -> OutputPaths {
        let stem = out
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "design".into());
        let dir = out.parent().map(Path::to_path_buf).unwrap_or_default();
        OutputPaths {
            design: out.to_path_buf(),
            meshes: dir.join(format!("{stem}_meshes")),
            report: report.map(Path::to_path_buf),
        }
    }

    fn all(&self) -> Vec<&Path> {
        let mut v = vec![self.design.as_path(), self.meshes.as_path()];
        if let Some(r) = &self.report {
            v.push(r);
        }
        v
    }
}

fn canonical(p: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(p).ok()
}

/// Refuses to overwrite (without `force`) or to touch the input.
pub fn check_outputs(input: &Path, paths: &OutputPaths, force: bool) -> Result<(), ImportError> {
    let input_c = canonical(input).unwrap_or_else(|| input.to_path_buf());
    for p in paths.all() {
        if let Some(c) = canonical(p)
            && input_c.starts_with(&c)
        {
            return Err(ImportError::Output {
                path: p.to_path_buf(),
                msg: format!("refusing to write over the input {}", input.display()),
            });
        }
        if p.exists() && !force {
            return Err(ImportError::Output {
                path: p.to_path_buf(),
                msg: "already exists (use --force to replace it)".into(),
            });
        }
    }
    let mut seen = Vec::new();
    for p in paths.all() {
        if seen.contains(&p) {
            return Err(ImportError::Output {
                path: p.to_path_buf(),
                msg: "two outputs would go to the same path".into(),
            });
        }
        seen.push(p);
    }
    Ok(())
}

fn tmp_of(p: &Path) -> PathBuf {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    p.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

fn remove_any(p: &Path) {
    if p.is_dir() {
        let _ = std::fs::remove_dir_all(p);
    } else {
        let _ = std::fs::remove_file(p);
    }
}

/// Writes all outputs atomically (see the module docs).
pub fn write_outputs(
    imported: &Imported,
    input: &Path,
    paths: &OutputPaths,
    force: bool,
) -> Result<(), ImportError> {
    check_outputs(input, paths, force)?;
    let staged: Vec<(PathBuf, PathBuf)> = paths
        .all()
        .into_iter()
        .map(|p| (tmp_of(p), p.to_path_buf()))
        .collect();
    let result = stage(imported, paths, &staged).and_then(|_| commit(&staged));
    if result.is_err() {
        for (tmp, _) in &staged {
            remove_any(tmp);
        }
    }
    result
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ImportError + '_ {
    move |e| ImportError::Output {
        path: path.to_path_buf(),
        msg: e.to_string(),
    }
}

fn stage(
    imported: &Imported,
    paths: &OutputPaths,
    staged: &[(PathBuf, PathBuf)],
) -> Result<(), ImportError> {
    let (design_tmp, meshes_tmp) = (&staged[0].0, &staged[1].0);
    for (tmp, fin) in staged {
        if let Some(dir) = fin.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io(dir))?;
        }
        remove_any(tmp);
    }
    let header = format!(
        "# SDRS design space imported by `sdrs import` from {}\n# Scene schema version 1 (see src/scene/schema.rs); hull OBJs in {}/\n# Decomposer: {}; ties: {} ({})\n",
        imported.report.input,
        paths
            .meshes
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        imported.report.decomposer,
        imported.report.ties,
        match imported.report.ties {
            "corners" => "coincident grid-block corners are one variable",
            _ =>
                "one auxiliary vertex per pair of touching or overlapping hulls; other vertices free",
        }
    );
    let yaml = header + &super::write::to_yaml(&with_surface_meshes(imported, paths));
    std::fs::write(design_tmp, yaml).map_err(io(&paths.design))?;
    std::fs::create_dir_all(meshes_tmp).map_err(io(&paths.meshes))?;
    for l in &imported.links {
        let mut obj = format!("# hulls of link {}\n", l.name);
        let mut base = 1;
        for (k, h) in l.hulls.iter().enumerate() {
            let Ok(p) = convex_hull(h) else { continue };
            obj.push_str(&format!("o hull_{k}\n"));
            for v in &p.vertices {
                obj.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
            }
            for t in &p.triangles {
                obj.push_str(&format!(
                    "f {} {} {}\n",
                    t[0] + base,
                    t[1] + base,
                    t[2] + base
                ));
            }
            base += p.vertices.len();
        }
        let f = meshes_tmp.join(format!("{}.obj", super::source::sanitize(&l.name)));
        std::fs::write(&f, obj).map_err(io(&paths.meshes))?;
        if !l.sources.is_empty() {
            let f = meshes_tmp.join(source_obj_name(&l.name));
            std::fs::write(&f, sources_obj(l)).map_err(io(&paths.meshes))?;
        }
    }
    if let (Some(r), Some((tmp, _))) = (&paths.report, staged.get(2)) {
        let json =
            serde_json::to_string_pretty(&imported.report).map_err(|e| ImportError::Output {
                path: r.clone(),
                msg: e.to_string(),
            })?;
        std::fs::write(tmp, json).map_err(io(r))?;
    }
    Ok(())
}

/// `<link>.source.obj`: the link's source surface (IPC `contact.ipc.surface: source`).
fn source_obj_name(link: &str) -> String {
    format!("{}.source.obj", super::source::sanitize(link))
}

/// The link's source meshes in its frame, one OBJ object per mesh (each a
/// separate component of the IPC surface).
fn sources_obj(l: &super::ImportedLink) -> String {
    let mut obj = format!("# source meshes of link {} (link frame)\n", l.name);
    let mut base = 1;
    for (k, m) in l.sources.iter().enumerate() {
        obj.push_str(&format!("o source_{k}\n"));
        for v in &m.vertices {
            obj.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
        }
        for t in &m.triangles {
            obj.push_str(&format!(
                "f {} {} {}\n",
                t[0] + base,
                t[1] + base,
                t[2] + base
            ));
        }
        base += m.vertices.len();
    }
    obj
}

/// The scene with each link's `surface_mesh` pointing at its
/// `<stem>_meshes/<link>.source.obj` (relative to the design file).
fn with_surface_meshes(imported: &Imported, paths: &OutputPaths) -> crate::scene::SceneSpec {
    let mut scene = imported.scene.clone();
    let dir = paths
        .meshes
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    for r in &mut scene.robots {
        for link in &mut r.links {
            if imported
                .links
                .iter()
                .any(|l| l.name == link.name && !l.sources.is_empty())
            {
                link.surface_mesh = Some(format!("{dir}/{}", source_obj_name(&link.name)));
            }
        }
    }
    scene
}

/// Renames staged outputs into place, design last; undoes on failure.
fn commit(staged: &[(PathBuf, PathBuf)]) -> Result<(), ImportError> {
    let mut order: Vec<&(PathBuf, PathBuf)> = staged.iter().skip(1).collect();
    order.push(&staged[0]);
    let mut done: Vec<&Path> = Vec::new();
    for (tmp, fin) in order {
        remove_any(fin);
        if let Err(e) = std::fs::rename(tmp, fin) {
            for d in done {
                remove_any(d);
            }
            return Err(io(fin)(e));
        }
        done.push(fin);
    }
    Ok(())
}

/// Scene → YAML: block mappings in field order, sequences of scalars in flow
/// style (`[x, y, z]`), floats always with a `.` (readable by YAML 1.1
/// parsers such as PyYAML too).
pub fn to_yaml<T: serde::Serialize>(value: &T) -> String {
    let v = serde_yaml::to_value(value).expect("scene serializes");
    let mut out = String::new();
    emit(&v, 0, &mut out, false);
    out
}

fn scalar(v: &serde_yaml::Value) -> Option<String> {
    use serde_yaml::Value as V;
    Some(match v {
        V::Null => "~".into(),
        V::Bool(b) => b.to_string(),
        V::Number(n) => {
            if let Some(i) = n.as_i64().filter(|_| !n.is_f64()) {
                i.to_string()
            } else if let Some(u) = n.as_u64().filter(|_| !n.is_f64()) {
                u.to_string()
            } else {
                float(n.as_f64().unwrap_or(f64::NAN))
            }
        }
        V::String(s) => serde_json::to_string(s).unwrap_or_default(),
        _ => return None,
    })
}

fn float(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            ".nan".into()
        } else if x > 0.0 {
            ".inf".into()
        } else {
            "-.inf".into()
        };
    }
    let s = serde_json::Number::from_f64(x)
        .map(|n| n.to_string())
        .unwrap_or_default();
    if s.contains('.') {
        s
    } else if let Some(i) = s.find(['e', 'E']) {
        format!("{}.0{}", &s[..i], &s[i..])
    } else {
        format!("{s}.0")
    }
}

fn emit(v: &serde_yaml::Value, indent: usize, out: &mut String, inline_first: bool) {
    use serde_yaml::Value as V;
    let pad = " ".repeat(indent);
    match v {
        V::Mapping(m) => {
            if m.is_empty() {
                out.push_str("{}\n");
                return;
            }
            for (k, (key, val)) in m.iter().enumerate() {
                if !(k == 0 && inline_first) {
                    out.push_str(&pad);
                }
                let key = scalar(key).unwrap_or_default();
                let key = key.trim_matches('"').to_string();
                out.push_str(&key);
                out.push(':');
                write_value(val, indent, out);
            }
        }
        V::Sequence(s) => {
            for item in s {
                out.push_str(&pad);
                out.push('-');
                if !matches!(item, V::Sequence(inner) if !inner.iter().all(|x| scalar(x).is_some()))
                {
                    out.push(' ');
                }
                match item {
                    V::Mapping(m) if m.len() <= 4 && m.iter().all(|(_, v)| scalar(v).is_some()) => {
                        out.push_str(&inline(item));
                        out.push('\n');
                    }
                    V::Mapping(_) => emit(item, indent + 2, out, true),
                    V::Tagged(t) => {
                        out.push_str(&t.tag.to_string());
                        write_value(&t.value, indent, out);
                    }
                    V::Sequence(inner) if !inner.iter().all(|x| scalar(x).is_some()) => {
                        out.push('\n');
                        emit(item, indent + 2, out, false);
                    }
                    _ => {
                        out.push_str(&inline(item));
                        out.push('\n');
                    }
                }
            }
        }
        V::Tagged(t) => emit(&t.value, indent, out, inline_first),
        _ => {
            out.push_str(&scalar(v).unwrap_or_default());
            out.push('\n');
        }
    }
}

fn inline(v: &serde_yaml::Value) -> String {
    use serde_yaml::Value as V;
    match v {
        V::Sequence(s) => format!("[{}]", s.iter().map(inline).collect::<Vec<_>>().join(", ")),
        V::Mapping(m) => format!(
            "{{{}}}",
            m.iter()
                .map(|(k, v)| format!(
                    "{}: {}",
                    scalar(k).unwrap_or_default().trim_matches('"'),
                    inline(v)
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        V::Tagged(t) => format!("{} {}", t.tag, inline(&t.value)),
        _ => scalar(v).unwrap_or_default(),
    }
}

fn write_value(val: &serde_yaml::Value, indent: usize, out: &mut String) {
    use serde_yaml::Value as V;
    let flat = |s: &Vec<V>| {
        s.iter().all(|x| {
            scalar(x).is_some()
                || matches!(x, V::Sequence(i) if i.iter().all(|y| scalar(y).is_some()))
        })
    };
    match val {
        V::Mapping(m) if m.is_empty() => out.push_str(" {}\n"),
        V::Mapping(m)
            if m.len() <= 2
                && m.iter().all(|(_, v)| {
                    scalar(v).is_some()
                        || matches!(v, V::Sequence(s) if s.iter().all(|x| scalar(x).is_some()))
                }) =>
        {
            out.push(' ');
            out.push_str(&inline(val));
            out.push('\n');
        }
        V::Mapping(_) => {
            out.push('\n');
            emit(val, indent + 2, out, false);
        }
        V::Sequence(s) if s.is_empty() => out.push_str(" []\n"),
        V::Sequence(s) if s.iter().all(|x| scalar(x).is_some()) => {
            out.push(' ');
            out.push_str(&inline(val));
            out.push('\n');
        }
        V::Sequence(s) if flat(s) => {
            // A list of points: one `[x, y, z]` per line.
            out.push('\n');
            for item in s {
                out.push_str(&" ".repeat(indent + 2));
                out.push_str("- ");
                out.push_str(&inline(item));
                out.push('\n');
            }
        }
        V::Sequence(_) => {
            out.push('\n');
            emit(val, indent + 2, out, false);
        }
        V::Tagged(t) => {
            // Externally tagged enum (a hull): `!vertices` / `!box`, the
            // form serde_yaml reads.
            out.push(' ');
            out.push_str(&t.tag.to_string());
            write_value(&t.value, indent, out);
        }
        _ => {
            out.push(' ');
            out.push_str(&scalar(val).unwrap_or_default());
            out.push('\n');
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn floats_always_carry_a_dot() {
        assert_eq!(super::float(1.0), "1.0");
        assert_eq!(super::float(1e-7), "1.0e-7");
        assert_eq!(super::float(-0.25), "-0.25");
        assert_eq!(super::float(2.5e20), "2.5e+20");
    }

    #[test]
    fn design_yaml_round_trips_exactly() {
        let input = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("robots/parallel_jaw_gripper/parallel_jaw_gripper.urdf");
        let opts = crate::import::ImportOptions::default();
        let imp = crate::import::import(&input, &opts).unwrap();
        let yaml = super::to_yaml(&imp.scene);
        let back: crate::scene::SceneSpec = serde_yaml::from_str(&yaml).unwrap();
        assert_eq!(back, imp.scene);
        assert!(yaml.contains("vertices:") && yaml.contains("ties:"));
    }
}
