//! `sdrs schema scene|task`: the printed schema (generated from the spec
//! types) names every key the bundled files use, describes every property,
//! and rejects what the loaders reject.

use crate::support;

use serde_json::Value;
use support::{robots, scratch_dir, sdrs};

fn schema(kind: &str, format: &str) -> String {
    let out = support::run_ok(sdrs().args(["schema", kind, "--format", format]));
    String::from_utf8(out.stdout).unwrap()
}

/// The schema as JSON, checked to equal its YAML rendering.
fn schema_value(kind: &str) -> Value {
    let json: Value = serde_json::from_str(&schema(kind, "json")).unwrap();
    let yaml: Value = serde_yaml::from_str(&schema(kind, "yaml")).unwrap();
    assert_eq!(json, yaml, "{kind}: YAML and JSON differ");
    json
}

/// The top-level keys of a YAML file.
fn keys(file: &std::path::Path) -> Vec<String> {
    let v: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    v.as_mapping()
        .unwrap()
        .keys()
        .map(|k| k.as_str().unwrap().to_string())
        .collect()
}

/// Every property of every object in the schema, with its description (or
/// none), as `(where, name, has description)`.
fn properties(v: &Value, at: &str, out: &mut Vec<(String, String, bool)>) {
    match v {
        Value::Object(m) => {
            if let Some(Value::Object(props)) = m.get("properties") {
                // A variant's tag (`type: link_point`, a constant) and the
                // single key of an externally tagged variant (`window:`, the
                // variant's own description) describe themselves.
                let variant = props.len() == 1 && m.contains_key("description");
                for (k, p) in props {
                    let described =
                        p.get("description").is_some() || p.get("const").is_some() || variant;
                    out.push((at.to_string(), k.clone(), described));
                }
            }
            for (k, c) in m {
                properties(c, &format!("{at}/{k}"), out);
            }
        }
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, c)| properties(c, &format!("{at}/{i}"), out)),
        _ => {}
    }
}

fn check(kind: &str, file: &std::path::Path) -> Value {
    let s = schema_value(kind);
    let props = s["properties"].as_object().unwrap();
    for k in keys(file) {
        assert!(props.contains_key(&k), "{kind}: `{k}` of {file:?} missing");
    }
    assert!(!props.contains_key("bogus"));
    assert_eq!(s["additionalProperties"], Value::Bool(false), "{kind}");
    let mut all = Vec::new();
    properties(&s, "", &mut all);
    assert!(all.len() > 20, "{kind}: {} properties", all.len());
    let bare: Vec<_> = all.iter().filter(|p| !p.2).collect();
    assert!(bare.is_empty(), "{kind}: undocumented properties {bare:?}");
    s
}

#[test]
fn the_scene_schema_names_every_key_and_describes_it() {
    let file = robots("four_chains.yaml");
    let s = check("scene", &file);
    // One level down: the keys of the bundled scene's robots.
    let scene: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let robot = s["$defs"]["RobotSpec"]["properties"].as_object().unwrap();
    for r in scene["robots"].as_sequence().unwrap() {
        for k in r.as_mapping().unwrap().keys() {
            assert!(robot.contains_key(k.as_str().unwrap()), "{k:?}");
        }
    }
    // Units and defaults come from the code's doc comments.
    let dt = s["properties"]["dt"]["description"].as_str().unwrap();
    assert!(dt.contains("(s)"), "{dt}");
    assert_eq!(s["properties"]["steps"]["default"], 1000);
}

#[test]
fn the_task_schema_names_every_key_and_describes_it() {
    let s = check("task", &robots("chain_reach/task.yaml"));
    let text = serde_json::to_string(&s).unwrap();
    for variant in ["link_point", "joint", "com", "relative"] {
        assert!(text.contains(&format!("\"{variant}\"")), "{variant}");
    }
}

#[test]
fn a_key_the_schema_lacks_is_rejected_by_the_loader() {
    // additionalProperties: false is the truth: the scene loader refuses
    // the key too, naming it.
    let dir = scratch_dir("schema-unknown-key");
    let scene = dir.join("scene.yaml");
    let text = std::fs::read_to_string(robots("four_chains.yaml")).unwrap();
    std::fs::write(&scene, format!("{text}\nbogus: 1\n")).unwrap();
    let out = sdrs()
        .args(["simulate", "-q", "--steps", "1"])
        .arg(&scene)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("bogus"), "{err}");
}
