//! Typed import errors. Every variant names the file and, where there is
//! one, the element (link, joint, mesh) so the user can find the problem.

use std::path::PathBuf;

/// Why an import failed.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The cause is part of the message (not a separate `source`), so a
    /// cause chain prints it once.
    #[error("{}: cannot read the file: {err}", path.display())]
    Io { path: PathBuf, err: std::io::Error },
    #[error("{}: malformed URDF XML{}: {msg}", path.display(), at_line(*line))]
    MalformedXml {
        path: PathBuf,
        line: Option<usize>,
        msg: String,
    },
    #[error("{}: {element}: {msg}", path.display())]
    InvalidUrdf {
        path: PathBuf,
        element: String,
        msg: String,
    },
    #[error(
        "{}: joint \"{joint}\": unsupported joint type \"{kind}\" (supported: revolute, continuous, prismatic, fixed, floating, spherical)",
        path.display()
    )]
    UnsupportedJoint {
        path: PathBuf,
        joint: String,
        kind: String,
    },
    #[error("{}: {element}: {msg}", path.display())]
    InvalidMjcf {
        path: PathBuf,
        element: String,
        msg: String,
    },
    #[error("{}: kinematic loop: {msg}", path.display())]
    KinematicLoop { path: PathBuf, msg: String },
    #[error("{}: {element}: mesh file {} not found{hint}", path.display(), mesh.display())]
    MissingMesh {
        /// The file that referenced the mesh (URDF), or the mesh itself.
        path: PathBuf,
        element: String,
        mesh: PathBuf,
        hint: String,
    },
    #[error("{}: {element}: cannot read mesh {}: {msg}", path.display(), mesh.display())]
    BadMesh {
        path: PathBuf,
        element: String,
        mesh: PathBuf,
        msg: String,
    },
    #[error("{}: {element}: mesh {} is empty (no triangles)", path.display(), mesh.display())]
    EmptyMesh {
        path: PathBuf,
        element: String,
        mesh: PathBuf,
    },
    #[error(
        "{}: {element}: mesh format \".{ext}\" of {} is not supported (supported: .obj, .stl, .dae); convert it first, e.g. `python -c \"import trimesh; trimesh.load('{}', force='mesh').export('{}.obj')\"`, or with MeshLab/Blender (File → Export → OBJ)",
        path.display(), mesh.display(), file_name(mesh), file_stem(mesh)
    )]
    UnsupportedFormat {
        path: PathBuf,
        element: String,
        mesh: PathBuf,
        ext: String,
    },
    #[error("{}: {element}: {msg}", path.display())]
    Geometry {
        path: PathBuf,
        element: String,
        msg: String,
    },
    #[error("{}: {element}: decomposition failed: {msg}", path.display())]
    Decomposition {
        path: PathBuf,
        element: String,
        msg: String,
    },
    #[error("{msg}")]
    Python { msg: String },
    /// The decomposition cache (`--cache`) could not be used.
    #[error("{}: {msg}", path.display())]
    Cache { path: PathBuf, msg: String },
    /// An option value no import can use; the message names the option.
    #[error("{msg}")]
    Options { msg: String },
    #[error("{}: {msg}", path.display())]
    Output { path: PathBuf, msg: String },
    #[error("{}: the imported design does not validate: {msg}", path.display())]
    Invalid { path: PathBuf, msg: String },
}

fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(" (line {l})")).unwrap_or_default()
}

fn file_name(p: &std::path::Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn file_stem(p: &std::path::Path) -> String {
    p.file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
