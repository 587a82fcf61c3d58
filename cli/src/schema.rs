//! `sdrs schema scene|task`: the JSON Schema of scene and task files,
//! generated from the spec types (`sdrs::scene::SceneSpec`,
//! `sdrs::optimize::TaskSpec` and what they contain) by `schemars`, so the
//! doc comments of the fields are the descriptions and the printed schema
//! cannot drift from what the loaders accept (unknown keys are rejected:
//! `additionalProperties: false`).

use anyhow::{Context, Result};
use schemars::schema_for;

/// Which file format to describe.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Kind {
    /// A scene file (`sdrs simulate SCENE.yaml`).
    Scene,
    /// A co-design task file (`sdrs optimize TASK.yaml`).
    Task,
}

/// How to print it.
#[derive(Clone, Copy, Debug, Default, clap::ValueEnum)]
pub enum Format {
    /// YAML (the scene and task files' own format); default.
    #[default]
    Yaml,
    /// JSON (a JSON Schema, draft 2020-12, for editors and validators).
    Json,
}

#[derive(clap::Args)]
pub struct SchemaArgs {
    /// `scene` or `task`.
    #[arg(value_enum)]
    pub kind: Kind,
    /// Output format.
    #[arg(long, value_enum, default_value = "yaml")]
    pub format: Format,
}

/// The schema of `kind` as a JSON value.
pub fn schema(kind: Kind) -> serde_json::Value {
    match kind {
        Kind::Scene => schema_for!(sdrs::scene::SceneSpec).to_value(),
        Kind::Task => schema_for!(sdrs::optimize::TaskSpec).to_value(),
    }
}

pub fn run(a: SchemaArgs) -> Result<()> {
    let v = schema(a.kind);
    let text = match a.format {
        Format::Json => serde_json::to_string_pretty(&v).context("printing the schema")? + "\n",
        Format::Yaml => serde_yaml::to_string(&v).context("printing the schema")?,
    };
    print!("{text}");
    Ok(())
}
