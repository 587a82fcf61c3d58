//! A tolerant pass over URDF text before `urdf-rs` parses it, accepting what
//! pybullet's and ROS's readers accept (each repair is reported):
//!
//! - numeric attributes written with commas (`xyz="0.07, 0, -0.69"`), a
//!   trailing dot (`lower="-1.57."`), xacro leftovers with a default
//!   (`rpy="$(optenv VAR 0 -1.5708 3.1416)"` → the default), or more numbers
//!   than the attribute holds (`rpy="a b c d"` → the first three, as pybullet
//!   reads them);
//! - top-level elements other than `<link>`, `<joint>` and `<material>`
//!   (`<gazebo>`, `<transmission>`, …) are dropped: they describe other
//!   simulators and controllers (each `<transmission>` gets its own line
//!   with its joints and `mechanicalReduction`: [`transmission_notes`]);
//! - a repeated singleton child (a second `<axis>` in a joint) is dropped;
//!   the first one counts, as in tinyxml-based readers; so is anything but a
//!   shape inside `<geometry>` (a misplaced `<material>`);
//! - a joint `<limit>` without `effort` or `velocity` gets `0` (pybullet's
//!   default; they are reported, not simulated);
//! - pybullet's `<plane>` and `<cdf>` shapes are replaced by a placeholder
//!   and recorded ([`super::pybullet_shapes`]), to be substituted after
//!   parsing.
//!
//! - cosmetic material parts `urdf-rs` would refuse (a `<texture/>` without
//!   a filename, a `<color>` without rgba, a `<material>` without a name)
//!   are dropped: materials are not imported.
//!
//! Anything else is left for the strict checks (`urdf::prescan`) to reject
//! with the line and element.

use super::pybullet_shapes::{Slot, Special, SpecialShapes};
use quick_xml::Writer;
use quick_xml::events::{BytesStart, Event};
use std::collections::{BTreeSet, HashSet};

/// How many numbers a URDF attribute holds, for the attributes read as
/// numbers (`None`: not numeric).
pub fn numeric_count(element: &str, attribute: &str) -> Option<usize> {
    match (element, attribute) {
        ("origin", "xyz" | "rpy") | ("axis", "xyz") | ("box", "size") | ("mesh", "scale") => {
            Some(3)
        }
        ("color", "rgba") => Some(4),
        ("cylinder" | "capsule", "radius" | "length")
        | ("sphere", "radius")
        | ("mass", "value")
        | ("inertia", "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz")
        | ("limit", "lower" | "upper" | "effort" | "velocity")
        | ("dynamics", "damping" | "friction")
        | ("mimic", "multiplier" | "offset") => Some(1),
        _ => None,
    }
}

/// The value of a numeric attribute as `count` numbers, repaired as the
/// module doc says; `None` when it cannot be (too few numbers, or a token
/// that is no number). The flag says whether anything was repaired.
pub fn normalize_value(value: &str, count: usize) -> Option<(String, bool)> {
    let mut v = value.trim();
    if let Some(inner) = v.strip_prefix("$(optenv").and_then(|s| s.strip_suffix(')')) {
        // `$(optenv NAME default…)`: the default.
        let mut parts = inner.split_whitespace();
        parts.next()?;
        let rest: Vec<&str> = parts.collect();
        let joined = rest.join(" ");
        return normalize_value(&joined, count).map(|(s, _)| (s, true));
    }
    let replaced;
    if v.contains(',') {
        replaced = v.replace(',', " ");
        v = &replaced;
    }
    let mut out = Vec::with_capacity(count);
    for tok in v.split_whitespace() {
        let t = if tok.parse::<f64>().is_ok() {
            tok
        } else {
            let t = tok.trim_end_matches('.');
            t.parse::<f64>().ok()?;
            t
        };
        out.push(t);
    }
    if out.len() < count {
        return None;
    }
    let repaired = out.len() > count || value.contains(',') || out.join(" ") != value.trim();
    out.truncate(count);
    Some((out.join(" "), repaired))
}

/// Geometry shapes (the ones `urdf-rs` knows, and the ones pybullet adds,
/// which the strict parser then reports as unsupported).
fn is_shape(name: &str) -> bool {
    matches!(
        name,
        "box" | "cylinder" | "capsule" | "sphere" | "mesh" | "plane" | "cdf" | "heightfield"
    )
}

/// Children of which only the first counts.
fn singleton(parent: &str, child: &str) -> bool {
    match parent {
        "joint" => matches!(
            child,
            "axis"
                | "origin"
                | "limit"
                | "parent"
                | "child"
                | "dynamics"
                | "calibration"
                | "mimic"
                | "safety_controller"
        ),
        "link" => child == "inertial",
        "collision" | "visual" => matches!(child, "origin" | "geometry"),
        "inertial" => matches!(child, "origin" | "mass" | "inertia"),
        _ => false,
    }
}

/// The tolerant pass's output.
#[derive(Debug, Default)]
pub struct Normalized {
    /// The repaired URDF text.
    pub text: String,
    /// What was repaired, in words.
    pub notes: Vec<String>,
    /// pybullet shapes replaced by placeholders.
    pub special: SpecialShapes,
}

/// The repaired text and what was repaired. On malformed XML the text is
/// returned unchanged (the strict checks report it with its line).
pub fn normalize(text: &str) -> Normalized {
    let mut n = rewrite(text).unwrap_or_else(|_| Normalized {
        text: text.to_string(),
        ..Normalized::default()
    });
    n.notes.extend(transmission_notes(text));
    n
}

/// One report line per top-level `<transmission>` (dropped: the scene has
/// no actuator model, the import's PD hold drives the joints): its name and
/// type, its joints, its actuators and every `mechanicalReduction` (ROS's
/// `<actuator><mechanicalReduction>` and the older direct child). When the
/// text does not parse here, one generic line if it has any.
pub fn transmission_notes(text: &str) -> Vec<String> {
    let Ok(doc) = roxmltree::Document::parse(text) else {
        return if text.contains("<transmission") {
            vec!["ignored <transmission> elements (they describe controllers)".into()]
        } else {
            Vec::new()
        };
    };
    let named = |n: &roxmltree::Node, tag: &str| -> Vec<String> {
        n.children()
            .filter(|c| c.has_tag_name(tag))
            .map(|c| format!("\"{}\"", c.attribute("name").unwrap_or("?")))
            .collect()
    };
    let reduction = |n: &roxmltree::Node| -> Vec<String> {
        n.descendants()
            .filter(|c| c.has_tag_name("mechanicalReduction"))
            .map(|c| c.text().unwrap_or("").trim().to_string())
            .collect()
    };
    doc.root_element()
        .children()
        .filter(|t| t.has_tag_name("transmission"))
        .map(|t| {
            let kind = t
                .children()
                .find(|c| c.has_tag_name("type"))
                .and_then(|c| c.text())
                .or(t.attribute("type"))
                .unwrap_or("no type")
                .trim();
            let joints = named(&t, "joint");
            let actuators = named(&t, "actuator");
            let red = reduction(&t);
            format!(
                "ignored <transmission> \"{}\" ({kind}): joint(s) [{}], actuator(s) [{}], mechanicalReduction [{}]; the scene has no actuator model (the import's PD hold drives the joints)",
                t.attribute("name").unwrap_or("?"),
                joints.join(", "),
                actuators.join(", "),
                red.join(", ")
            )
        })
        .collect()
}

/// Where the rewrite is: the current link and how many `<collision>` and
/// `<visual>` elements of it have been seen.
#[derive(Default)]
struct LinkCursor {
    name: String,
    collisions: usize,
    visuals: usize,
}

fn rewrite(text: &str) -> Result<Normalized, quick_xml::Error> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut writer = Writer::new(Vec::with_capacity(text.len()));
    let mut stack: Vec<(String, HashSet<String>)> = Vec::new();
    let mut notes = BTreeSet::new();
    let mut special = SpecialShapes::new();
    let mut link = LinkCursor::default();
    let mut skip_depth = 0usize;
    loop {
        let ev = reader.read_event()?;
        if skip_depth > 0 {
            match ev {
                Event::Start(_) => skip_depth += 1,
                Event::End(_) => skip_depth -= 1,
                Event::Eof => break,
                _ => {}
            }
            continue;
        }
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let is_start = matches!(ev, Event::Start(_));
                let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                let parent = stack.last().map(|(p, _)| p.clone());
                if let Some(note) = cosmetic_problem(e, &name, parent.as_deref()) {
                    notes.insert(note);
                    if is_start {
                        skip_depth = 1;
                    }
                    continue;
                }
                let drop = match parent.as_deref() {
                    Some("robot") if stack.len() == 1 => {
                        let keep = matches!(name.as_str(), "link" | "joint" | "material");
                        // Transmissions get a line each ([`transmission_notes`]).
                        if !keep && name != "transmission" {
                            notes.insert(format!(
                                "ignored <{name}> elements (they describe other simulators or controllers)"
                            ));
                        }
                        !keep
                    }
                    Some("geometry") if !is_shape(&name) => {
                        notes.insert(format!("dropped a <{name}> misplaced inside a <geometry>"));
                        true
                    }
                    Some(p) if singleton(p, &name) => {
                        let seen = &mut stack.last_mut().expect("parent").1;
                        let dup = !seen.insert(name.clone());
                        if dup {
                            notes.insert(format!(
                                "dropped a repeated <{name}> in a <{p}> (the first one counts)"
                            ));
                        }
                        dup
                    }
                    _ => false,
                };
                if drop {
                    if is_start {
                        skip_depth = 1;
                    }
                    continue;
                }
                let attr = |key: &str| {
                    e.try_get_attribute(key)
                        .ok()
                        .flatten()
                        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                        .unwrap_or_default()
                };
                match (parent.as_deref(), name.as_str()) {
                    (Some("robot"), "link") => {
                        link = LinkCursor {
                            name: attr("name"),
                            ..LinkCursor::default()
                        }
                    }
                    (Some("link"), "collision") => link.collisions += 1,
                    (Some("link"), "visual") => link.visuals += 1,
                    _ => {}
                }
                let in_slot = (stack.len() >= 2)
                    .then(|| stack[stack.len() - 2].0.as_str())
                    .and_then(|s| match s {
                        "collision" => Some((Slot::Collision, link.collisions.checked_sub(1)?)),
                        "visual" => Some((Slot::Visual, link.visuals.checked_sub(1)?)),
                        _ => None,
                    });
                let shape = match name.as_str() {
                    "plane" => Some(Special::Plane {
                        normal: attr("normal"),
                    }),
                    "cdf" => Some(Special::Cdf {
                        filename: attr("filename"),
                    }),
                    _ => None,
                };
                if let (Some("geometry"), Some((slot, index)), Some(shape)) =
                    (parent.as_deref(), in_slot, shape)
                {
                    special.insert((link.name.clone(), slot, index), shape);
                    writer.write_event(Event::Empty(
                        BytesStart::new("sphere").with_attributes([("radius", "1")]),
                    ))?;
                    if is_start {
                        skip_depth = 1;
                    }
                    continue;
                }
                let fixed = repair_attributes(e, &name, parent.as_deref(), &mut notes);
                if is_start {
                    stack.push((name, HashSet::new()));
                    writer.write_event(Event::Start(fixed))?;
                } else {
                    writer.write_event(Event::Empty(fixed))?;
                }
            }
            Event::End(e) => {
                stack.pop();
                writer.write_event(Event::End(e))?;
            }
            Event::Eof => break,
            other => writer.write_event(other)?,
        }
    }
    let out = String::from_utf8(writer.into_inner()).unwrap_or_else(|_| text.to_string());
    Ok(Normalized {
        text: out,
        notes: notes.into_iter().collect(),
        special,
    })
}

/// An attribute's unescaped value, if present.
fn attribute(e: &BytesStart<'_>, key: &str) -> Option<String> {
    e.try_get_attribute(key)
        .ok()
        .flatten()
        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
}

/// Why a cosmetic element is dropped (`None`: kept). Materials only colour
/// the visuals, which the import does not use; ROS and Pinocchio load files
/// whose materials `urdf-rs` would refuse: a `<texture/>` without a
/// filename (icub, romeo), a `<color>` without four numbers, a
/// `<material>` without a name.
fn cosmetic_problem(e: &BytesStart<'_>, name: &str, parent: Option<&str>) -> Option<String> {
    let blank = |key: &str| attribute(e, key).is_none_or(|v| v.trim().is_empty());
    match (parent, name) {
        (_, "material") if blank("name") => {
            Some("ignored a <material> without a name (cosmetic: materials are not imported)".into())
        }
        (Some("material"), "texture") if blank("filename") => Some(
            "ignored a <texture> without a filename in a <material> (cosmetic: materials are not imported)"
                .into(),
        ),
        (Some("material"), "color")
            if attribute(e, "rgba")
                .and_then(|v| normalize_value(&v, 4))
                .is_none() =>
        {
            Some("ignored a <color> without four rgba numbers in a <material> (cosmetic: materials are not imported)".into())
        }
        _ => None,
    }
}

fn repair_attributes<'a>(
    e: &BytesStart<'a>,
    name: &str,
    parent: Option<&str>,
    notes: &mut BTreeSet<String>,
) -> BytesStart<'static> {
    let mut out = BytesStart::new(name.to_string());
    let mut present = HashSet::new();
    for attr in e.attributes().flatten() {
        let key = String::from_utf8_lossy(attr.key.as_ref()).into_owned();
        let value = attr
            .unescape_value()
            .map(|v| v.into_owned())
            .unwrap_or_else(|_| String::from_utf8_lossy(&attr.value).into_owned());
        let value = match numeric_count(name, &key).and_then(|c| normalize_value(&value, c)) {
            Some((v, true)) => {
                notes.insert(format!(
                    "repaired <{name} {key}=\"{value}\"> to \"{v}\" (as pybullet reads it)"
                ));
                v
            }
            _ => value,
        };
        present.insert(key.clone());
        out.push_attribute((key.as_str(), value.as_str()));
    }
    if name == "limit" && parent == Some("joint") {
        for key in ["effort", "velocity"] {
            if !present.contains(key) {
                notes.insert(format!("a joint <limit> without {key} gets {key}=\"0\""));
                out.push_attribute((key, "0"));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_repaired_as_pybullet_reads_them() {
        let n = |v: &str, c| normalize_value(v, c);
        assert_eq!(n("0.07, 0, -0.69", 3), Some(("0.07 0 -0.69".into(), true)));
        assert_eq!(n("-1.57.", 1), Some(("-1.57".into(), true)));
        assert_eq!(
            n("$(optenv HUSKY_IMU_RPY 0 -1.5708 3.1416)", 3),
            Some(("0 -1.5708 3.1416".into(), true))
        );
        assert_eq!(
            n("-3.14159 1.57079 0 0", 3),
            Some(("-3.14159 1.57079 0".into(), true))
        );
        assert_eq!(n(" 1 2 3 ", 3), Some(("1 2 3".into(), false)));
        assert_eq!(n("1 x 1", 3), None);
        assert_eq!(n("0 0", 3), None);
    }

    #[test]
    fn documents_are_repaired_and_notes_say_how() {
        let text = r#"<robot name="r">
  <link name="a"><inertial><mass value="1,"/></inertial></link>
  <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
    <axis xyz="1 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1"/></joint>
  <gazebo reference="a"><material>Gazebo/Blue</material></gazebo>
  <link name="b"><visual><geometry><box size="1 1 1"/><material name="x"/></geometry></visual></link>
</robot>"#;
        let Normalized {
            text: out, notes, ..
        } = normalize(text);
        assert!(
            out.contains(r#"<axis xyz="1 0 0"/>"#) && !out.contains("0 1 0"),
            "{out}"
        );
        assert!(
            !out.contains("gazebo") && out.contains(r#"<link name="b">"#),
            "{out}"
        );
        assert!(!out.contains("material"), "{out}");
        assert!(
            out.contains(r#"effort="0""#) && out.contains(r#"velocity="0""#),
            "{out}"
        );
        assert!(out.contains(r#"<mass value="1"/>"#), "{out}");
        assert_eq!(notes.len(), 6, "{notes:?}");
        // Lines are kept where nothing was dropped.
        assert_eq!(out.lines().count(), text.lines().count());
    }
}
