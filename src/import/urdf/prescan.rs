//! Checks of the URDF text before urdf-rs parses it: malformed XML and
//! unknown joint types get errors naming the line or the joint; pybullet's
//! deformable bodies are refused with what they need.

use super::super::error::ImportError;
use quick_xml::events::Event;
use std::path::Path;

/// Why a file with a `<deformable>` and no `<link>` is refused, naming its
/// mesh and whether that mesh exists next to the file.
pub(super) fn deformable_message(path: &Path, text: &str) -> String {
    let mesh = text
        .split("<deformable")
        .nth(1)
        .and_then(|d| d.split("filename=\"").nth(1))
        .and_then(|f| f.split('"').next());
    let missing = match mesh {
        Some(m) => {
            let p = path.parent().unwrap_or(Path::new(".")).join(m);
            if p.is_file() {
                format!(" (its mesh {m} exists)")
            } else {
                format!("; its mesh {m} is not found either ({})", p.display())
            }
        }
        None => String::new(),
    };
    format!(
        "the URDF has no <link>: it describes a deformable body (pybullet's <deformable> soft-body extension), which this rigid-body method cannot represent{missing}"
    )
}

pub(super) fn line_of(text: &str, pos: usize) -> usize {
    text.as_bytes()[..pos.min(text.len())]
        .iter()
        .filter(|&&c| c == b'\n')
        .count()
        + 1
}

/// Well-formedness, joint types and numeric attributes.
pub(super) fn prescan(path: &Path, text: &str) -> Result<(), ImportError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack: Vec<String> = Vec::new();
    // `<link name="arm">`-style labels of the open elements, for messages.
    let mut labels: Vec<String> = Vec::new();
    let malformed = |line: usize, msg: String| ImportError::MalformedXml {
        path: path.to_path_buf(),
        line: Some(line),
        msg,
    };
    let mut saw_robot = false;
    loop {
        let pos = reader.buffer_position() as usize;
        let ev = reader.read_event().map_err(|e| {
            malformed(
                line_of(text, reader.error_position() as usize),
                e.to_string(),
            )
        })?;
        let (e, empty) = match &ev {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                stack.pop();
                labels.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
        if stack.is_empty() {
            if name != "robot" {
                return Err(malformed(
                    line_of(text, pos),
                    format!("the root element is <{name}>, expected <robot>"),
                ));
            }
            saw_robot = true;
        }
        if name == "joint" && stack.len() == 1 {
            let attr = |k: &str| -> Option<String> {
                e.try_get_attribute(k)
                    .ok()
                    .flatten()
                    .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
            };
            let jname = attr("name").unwrap_or_else(|| "<unnamed>".into());
            let kind = attr("type").unwrap_or_default();
            if !matches!(
                kind.as_str(),
                "revolute" | "continuous" | "prismatic" | "fixed" | "floating" | "spherical"
            ) {
                return Err(ImportError::UnsupportedJoint {
                    path: path.to_path_buf(),
                    joint: jname,
                    kind,
                });
            }
        }
        // Numeric attributes: the count and the numbers, with the line and
        // the element (urdf-rs reports neither).
        let label = |e: &quick_xml::events::BytesStart, name: &str| -> String {
            match e
                .try_get_attribute("name")
                .ok()
                .flatten()
                .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
            {
                Some(n) => format!("<{name} name=\"{n}\">"),
                None => format!("<{name}>"),
            }
        };
        for attr in e.attributes().flatten() {
            let key = String::from_utf8_lossy(attr.key.as_ref()).into_owned();
            let Some(count) = super::super::tolerant::numeric_count(&name, &key) else {
                continue;
            };
            let value = attr
                .unescape_value()
                .map(|v| v.into_owned())
                .unwrap_or_default();
            let tokens: Vec<&str> = value.split_whitespace().collect();
            let bad = tokens.iter().find(|s| s.parse::<f64>().is_err());
            if super::super::tolerant::normalize_value(&value, count).is_none() {
                let mut path: Vec<String> = labels.clone();
                path.push(label(e, &name));
                return Err(malformed(
                    line_of(text, pos),
                    format!(
                        "{}: attribute {key}=\"{value}\" must be {count} number{}{}",
                        path.join(" "),
                        if count == 1 { "" } else { "s" },
                        match bad {
                            Some(b) if b.trim_end_matches('.').parse::<f64>().is_err() => {
                                format!(" (\"{b}\" is not a number)")
                            }
                            _ => format!(", got {}", tokens.len()),
                        }
                    ),
                ));
            }
        }
        if !empty {
            labels.push(label(e, &name));
            stack.push(name);
        }
    }
    if let Some(open) = stack.last() {
        return Err(malformed(
            line_of(text, text.len()),
            format!("element <{open}> is not closed"),
        ));
    }
    if !saw_robot {
        return Err(malformed(1, "no <robot> element".into()));
    }
    Ok(())
}
