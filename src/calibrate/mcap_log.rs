//! Robot logs in MCAP (the ROS 2 / Foxglove container) as measured data:
//! `sdrs calibrate SCENE --measured run.mcap`.
//!
//! - **Reader**: the `mcap` crate's streaming reader over the whole file:
//!   header, schema, channel, message and chunk records (chunks
//!   uncompressed, `zstd` or `lz4`; any other compression is an error
//!   naming it), footer and end magic. A truncated file, a bad magic or a
//!   bad CRC is an error naming the last message read before it.
//! - **Topic**: one topic, [`DEFAULT_TOPIC`] unless [`LogMapping::topic`]
//!   names another (`--topic`); other topics are ignored; a topic absent
//!   from the file is an error listing the topics present.
//! - **Messages**: `sensor_msgs/msg/JointState`, either ROS 2 CDR
//!   (`message_encoding: cdr`, schema name `sensor_msgs/msg/JointState`,
//!   little- or big-endian encapsulation) or JSON (`message_encoding:
//!   json`) with the same fields: `header.stamp.{sec, nanosec}` (`nsec`
//!   accepted), `name`, `position`, `velocity`, `effort`. `position` must
//!   have one finite entry per name; `velocity` and `effort` must be empty
//!   or have one entry per name (ROS's convention) and are not used (the
//!   comparison is on coordinates, as with CSV).
//! - **Time**: each message's header stamp; a message without one (JSON
//!   without `header`, or a CDR stamp of exactly 0) uses its log time.
//!   Every message of the topic must use the same clock. The first
//!   message is `t = 0`: `t = (stamp − first stamp) / 10⁹` s, computed in
//!   integer nanoseconds and divided once. Times must increase strictly.
//! - **Joints**: each name is matched to the scene's coordinate of that
//!   name (the trajectory CSV's column names: `hinge`, `arm/elbow`) after
//!   the renames of [`LogMapping::rename`] (`--rename LOG=COORD`; `LOG=`
//!   ignores that joint). A name matching no coordinate is an error
//!   listing them; a rename whose joint never appears is an error. A joint
//!   absent from some messages has gaps there (as an empty CSV cell).
//!   Channels are ordered as the scene's coordinates.
//!
//! The result is a [`Measured`] validated as a CSV is ([`Measured::from_samples`]),
//! so alignment with the simulation is the CSV path's.

use super::CalibrateError;
use super::data::{Channel, Measured};
use crate::model::Model;
use std::collections::BTreeMap;
use std::path::Path;

/// The topic read unless another is named.
pub const DEFAULT_TOPIC: &str = "/joint_states";

/// The ROS 2 message type read (the schema name of CDR channels).
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";

/// How a robot log maps to the scene's coordinates (`--topic`, `--rename`).
#[derive(Clone, Debug, Default)]
pub struct LogMapping {
    /// The topic to read; `None`: [`DEFAULT_TOPIC`].
    pub topic: Option<String>,
    /// `(name in the log, scene coordinate)`; an empty coordinate ignores
    /// that joint.
    pub rename: Vec<(String, String)>,
}

impl LogMapping {
    /// The topic read.
    pub fn topic(&self) -> &str {
        self.topic.as_deref().unwrap_or(DEFAULT_TOPIC)
    }

    /// Parses `LOG=COORD` (`--rename`); an error message otherwise.
    pub fn parse_rename(s: &str) -> Result<(String, String), String> {
        let (a, b) = s.split_once('=').ok_or_else(|| {
            format!("\"{s}\": expected LOG_NAME=COORDINATE (or LOG_NAME= to ignore it)")
        })?;
        if a.trim().is_empty() {
            return Err(format!("\"{s}\": the log's joint name is empty"));
        }
        Ok((a.trim().to_string(), b.trim().to_string()))
    }
}

/// One decoded `JointState`.
#[derive(Clone, Debug, PartialEq)]
pub struct JointState {
    /// Header stamp (ns since the epoch); `None` when absent.
    pub stamp_ns: Option<i128>,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// A CDR reader: alignment is relative to the end of the 4-byte
/// encapsulation header.
struct Cdr<'a> {
    buf: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> Result<Self, String> {
        if data.len() < 4 {
            return Err(format!(
                "{} byte(s): shorter than the 4-byte CDR encapsulation header",
                data.len()
            ));
        }
        let little = match (data[0], data[1]) {
            (0, 1) | (0, 3) => true,
            (0, 0) | (0, 2) => false,
            (a, b) => {
                return Err(format!(
                    "unknown CDR encapsulation {a:#04x} {b:#04x} (plain CDR, little- or big-endian, is read)"
                ));
            }
        };
        Ok(Cdr {
            buf: &data[4..],
            pos: 0,
            little,
        })
    }

    fn take(&mut self, n: usize, align: usize, what: &str) -> Result<&'a [u8], String> {
        let start = self.pos.div_ceil(align) * align;
        let end = start.checked_add(n).filter(|&e| e <= self.buf.len());
        let Some(end) = end else {
            return Err(format!(
                "the message ends at byte {} while reading {what} ({n} more byte(s) needed at byte {})",
                self.buf.len() + 4,
                start + 4
            ));
        };
        self.pos = end;
        Ok(&self.buf[start..end])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, 4, what)?.try_into().unwrap();
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f64(&mut self, what: &str) -> Result<f64, String> {
        let b: [u8; 8] = self.take(8, 8, what)?.try_into().unwrap();
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        let b = self.take(n, 1, what)?;
        let b = b.strip_suffix(&[0]).unwrap_or(b);
        String::from_utf8(b.to_vec()).map_err(|_| format!("{what} is not UTF-8"))
    }

    /// A sequence length, bounded by the bytes left (a corrupt length
    /// must not allocate gigabytes).
    fn len(&mut self, what: &str, min_size: usize) -> Result<usize, String> {
        let n = self.u32(&format!("the length of {what}"))? as usize;
        if n.saturating_mul(min_size) > self.buf.len() - self.pos {
            return Err(format!(
                "{what} claims {n} entries, more than the message holds"
            ));
        }
        Ok(n)
    }

    fn f64_seq(&mut self, what: &str) -> Result<Vec<f64>, String> {
        let n = self.len(what, 8)?;
        (0..n).map(|k| self.f64(&format!("{what}[{k}]"))).collect()
    }
}

/// Decodes a CDR `sensor_msgs/msg/JointState`.
pub fn decode_cdr(data: &[u8]) -> Result<JointState, String> {
    let mut c = Cdr::new(data)?;
    let sec = c.u32("header.stamp.sec")? as i32;
    let nanosec = c.u32("header.stamp.nanosec")?;
    c.string("header.frame_id")?;
    let n = c.len("name", 4)?;
    let name = (0..n)
        .map(|k| c.string(&format!("name[{k}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let position = c.f64_seq("position")?;
    let velocity = c.f64_seq("velocity")?;
    let effort = c.f64_seq("effort")?;
    let stamp = i128::from(sec) * 1_000_000_000 + i128::from(nanosec);
    Ok(JointState {
        stamp_ns: (stamp != 0).then_some(stamp),
        name,
        position,
        velocity,
        effort,
    })
}

/// Decodes a JSON `JointState` (the fields of the ROS message).
pub fn decode_json(data: &[u8]) -> Result<JointState, String> {
    let v: serde_json::Value =
        serde_json::from_slice(data).map_err(|e| format!("not valid JSON: {e}"))?;
    let obj = v.as_object().ok_or("not a JSON object")?;
    let stamp_ns = match obj.get("header").and_then(|h| h.get("stamp")) {
        None | Some(serde_json::Value::Null) => None,
        Some(s) => {
            let int = |k: &str| s.get(k).and_then(serde_json::Value::as_i64);
            let sec = int("sec").ok_or("header.stamp has no integer `sec`")?;
            let ns = int("nanosec")
                .or_else(|| int("nsec"))
                .ok_or("header.stamp has no integer `nanosec` (or `nsec`)")?;
            Some(i128::from(sec) * 1_000_000_000 + i128::from(ns))
        }
    };
    let name = match obj.get("name") {
        Some(serde_json::Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(k, x)| {
                x.as_str()
                    .map(str::to_string)
                    .ok_or_else(|| format!("name[{k}] is not a string"))
            })
            .collect::<Result<Vec<_>, _>>()?,
        _ => return Err("no `name` array".into()),
    };
    let floats = |key: &str, required: bool| -> Result<Vec<f64>, String> {
        match obj.get(key) {
            None | Some(serde_json::Value::Null) if !required => Ok(Vec::new()),
            Some(serde_json::Value::Array(a)) => a
                .iter()
                .enumerate()
                .map(|(k, x)| {
                    x.as_f64()
                        .ok_or_else(|| format!("{key}[{k}] = {x} is not a number"))
                })
                .collect(),
            _ => Err(format!("no `{key}` array")),
        }
    };
    Ok(JointState {
        stamp_ns,
        position: floats("position", true)?,
        velocity: floats("velocity", false)?,
        effort: floats("effort", false)?,
        name,
    })
}

/// Checks one message's arrays: positions one finite value per name,
/// velocity and effort empty or one per name, no name twice.
fn check_arrays(js: &JointState) -> Result<(), String> {
    let n = js.name.len();
    if js.position.len() != n {
        return Err(format!(
            "{} position(s) for {n} name(s) (one position per joint name needed)",
            js.position.len()
        ));
    }
    for (key, v) in [("velocity", &js.velocity), ("effort", &js.effort)] {
        if !v.is_empty() && v.len() != n {
            return Err(format!(
                "{} {key} value(s) for {n} name(s) (empty or one per name)",
                v.len()
            ));
        }
    }
    for (k, (name, p)) in js.name.iter().zip(&js.position).enumerate() {
        if !p.is_finite() {
            return Err(format!(
                "joint \"{name}\": position[{k}] = {p} is not a finite number"
            ));
        }
        if js.name[..k].contains(name) {
            return Err(format!("joint \"{name}\" appears twice"));
        }
    }
    Ok(())
}

/// How the topic's messages are decoded.
#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    Cdr,
    Json,
}

/// The decoder for a channel, or why it cannot be read.
fn encoding_of(ch: &mcap::Channel) -> Result<Encoding, String> {
    let schema = ch.schema.as_ref().map(|s| s.name.as_str());
    match ch.message_encoding.as_str() {
        "cdr" => match schema {
            Some(JOINT_STATE) => Ok(Encoding::Cdr),
            Some(other) => Err(format!(
                "schema \"{other}\": only {JOINT_STATE} is read (CDR)"
            )),
            None => Err(format!(
                "CDR messages without a schema (expected {JOINT_STATE})"
            )),
        },
        "json" => Ok(Encoding::Json),
        other => Err(format!(
            "message encoding \"{other}\" is not read (cdr with schema {JOINT_STATE}, or json)"
        )),
    }
}

/// The samples of the topic, before they become channels.
struct Samples {
    /// Integer nanoseconds of each message on the topic.
    times_ns: Vec<i128>,
    /// Coordinate index → value per message.
    values: BTreeMap<usize, Vec<Option<f64>>>,
    /// Whether the header stamps were used (else log times).
    stamped: Option<bool>,
    /// The log names whose rename was used.
    renamed_seen: Vec<bool>,
}

/// Where a message sits, for errors.
struct At<'p> {
    path: &'p Path,
    topic: &'p str,
    index: usize,
    log_time: u64,
}

impl At<'_> {
    fn err(&self, msg: String) -> CalibrateError {
        CalibrateError::LogMessage {
            path: self.path.to_path_buf(),
            topic: self.topic.to_string(),
            index: self.index,
            log_time: self.log_time,
            msg,
        }
    }
}

/// The coordinate a log joint name maps to (`None`: ignored).
fn coordinate(
    model: &Model,
    mapping: &LogMapping,
    seen: &mut [bool],
    name: &str,
) -> Result<Option<usize>, String> {
    let target = match mapping.rename.iter().position(|(a, _)| a == name) {
        Some(k) => {
            seen[k] = true;
            mapping.rename[k].1.as_str()
        }
        None => name,
    };
    if target.is_empty() {
        return Ok(None);
    }
    match model.dofs.iter().position(|d| d.name == target) {
        Some(dof) => Ok(Some(dof)),
        None => {
            let known: Vec<&str> = model.dofs.iter().map(|d| d.name.as_str()).collect();
            let via = if target == name {
                String::new()
            } else {
                format!(" (renamed from \"{name}\")")
            };
            Err(format!(
                "joint \"{target}\"{via} is not a coordinate of the scene (its coordinates: {}); map it with --rename {name}=COORDINATE or ignore it with --rename {name}=",
                known.join(", ")
            ))
        }
    }
}

/// Adds one decoded message to `s`.
fn add_message(
    s: &mut Samples,
    js: &JointState,
    log_time: u64,
    model: &Model,
    mapping: &LogMapping,
    at: &At,
) -> Result<(), CalibrateError> {
    check_arrays(js).map_err(|m| at.err(m))?;
    let stamped = js.stamp_ns.is_some();
    match s.stamped {
        Some(prev) if prev != stamped => {
            return Err(at.err(if stamped {
                "has a header stamp while the earlier messages have none (log time used): one clock per topic".into()
            } else {
                "has no header stamp while the earlier messages have one: one clock per topic".into()
            }));
        }
        _ => s.stamped = Some(stamped),
    }
    let t = js.stamp_ns.unwrap_or(i128::from(log_time));
    if let Some(&prev) = s.times_ns.last().filter(|&&p| t <= p) {
        return Err(at.err(format!(
            "time does not increase: {} {t} ns, previous message {prev} ns ({:+} ns)",
            if stamped { "header stamp" } else { "log time" },
            t - prev
        )));
    }
    let k = s.times_ns.len();
    s.times_ns.push(t);
    for (name, &p) in js.name.iter().zip(&js.position) {
        let Some(dof) =
            coordinate(model, mapping, &mut s.renamed_seen, name).map_err(|m| at.err(m))?
        else {
            continue;
        };
        let v = s.values.entry(dof).or_default();
        v.resize(k + 1, None);
        if v[k].is_some() {
            return Err(at.err(format!(
                "joint \"{name}\" maps to coordinate \"{}\", which another joint of this message also maps to",
                model.dofs[dof].name
            )));
        }
        v[k] = Some(p);
    }
    Ok(())
}

/// Reads an MCAP log as measured data (see the module doc).
pub fn load(path: &Path, model: &Model, mapping: &LogMapping) -> Result<Measured, CalibrateError> {
    let bytes = std::fs::read(path).map_err(|source| CalibrateError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes, path, model, mapping)
}

/// Parses MCAP bytes; `path` is used in messages.
pub fn parse(
    bytes: &[u8],
    path: &Path,
    model: &Model,
    mapping: &LogMapping,
) -> Result<Measured, CalibrateError> {
    let topic = mapping.topic();
    let file_err = |msg: String| CalibrateError::Mcap {
        path: path.to_path_buf(),
        msg,
    };
    let stream = mcap::MessageStream::new(bytes).map_err(|e| file_err(describe(&e, None)))?;
    let mut s = Samples {
        times_ns: Vec::new(),
        values: BTreeMap::new(),
        stamped: None,
        renamed_seen: vec![false; mapping.rename.len()],
    };
    let mut topics: BTreeMap<String, usize> = BTreeMap::new();
    let mut encoding: Option<Encoding> = None;
    let mut last: Option<(usize, u64)> = None;
    for (read, msg) in stream.enumerate() {
        let msg = msg.map_err(|e| file_err(describe(&e, last)))?;
        last = Some((read + 1, msg.log_time));
        let count = topics.entry(msg.channel.topic.clone()).or_default();
        *count += 1;
        if msg.channel.topic != topic {
            continue;
        }
        let at = At {
            path,
            topic,
            index: *count,
            log_time: msg.log_time,
        };
        let enc = match encoding {
            Some(e) => e,
            None => *encoding.insert(encoding_of(&msg.channel).map_err(|m| {
                CalibrateError::LogTopic {
                    path: path.to_path_buf(),
                    topic: topic.to_string(),
                    msg: m,
                }
            })?),
        };
        let js = match enc {
            Encoding::Cdr => decode_cdr(&msg.data),
            Encoding::Json => decode_json(&msg.data),
        }
        .map_err(|m| at.err(m))?;
        add_message(&mut s, &js, msg.log_time, model, mapping, &at)?;
    }
    finish(s, path, model, topic, &topics, mapping)
}

/// The mcap crate's error in words, with the last message read before it.
fn describe(e: &mcap::McapError, last: Option<(usize, u64)>) -> String {
    let what = match e {
        mcap::McapError::BadMagic => {
            "bad magic: not an MCAP file (it must start and end with \\x89MCAP0\\r\\n)".to_string()
        }
        mcap::McapError::UnexpectedEof | mcap::McapError::BadFooter => {
            format!("truncated: {e} (the file ends before its footer and end magic)")
        }
        mcap::McapError::UnexpectedEoc => format!("a chunk is truncated: {e}"),
        mcap::McapError::UnsupportedCompression(c) => {
            format!("chunk compression \"{c}\" is not supported (uncompressed, zstd and lz4 are)")
        }
        other => other.to_string(),
    };
    match last {
        None => format!("{what} (before the first message)"),
        Some((n, t)) => format!("{what} (after message {n} of the file, log time {t} ns)"),
    }
}

/// The topic's samples as a validated [`Measured`].
fn finish(
    s: Samples,
    path: &Path,
    model: &Model,
    topic: &str,
    topics: &BTreeMap<String, usize>,
    mapping: &LogMapping,
) -> Result<Measured, CalibrateError> {
    let topic_err = |msg: String| CalibrateError::LogTopic {
        path: path.to_path_buf(),
        topic: topic.to_string(),
        msg,
    };
    if s.times_ns.is_empty() {
        let present: Vec<String> = topics
            .iter()
            .map(|(t, n)| format!("{t} ({n} messages)"))
            .collect();
        return Err(topic_err(format!(
            "no message on this topic (topics in the file: {}); choose one with --topic",
            if present.is_empty() {
                "none".to_string()
            } else {
                present.join(", ")
            }
        )));
    }
    if let Some(k) = s.renamed_seen.iter().position(|seen| !seen) {
        let (a, b) = &mapping.rename[k];
        return Err(topic_err(format!(
            "missing joint: \"{a}\" (--rename {a}={b}) is in no message of this topic"
        )));
    }
    if s.values.is_empty() {
        return Err(topic_err(
            "no joint of these messages is a coordinate of the scene (all ignored by --rename)"
                .into(),
        ));
    }
    let n = s.times_ns.len();
    let t0 = s.times_ns[0];
    let times: Vec<f64> = s.times_ns.iter().map(|&t| (t - t0) as f64 / 1e9).collect();
    let channels = s
        .values
        .into_iter()
        .map(|(dof, mut values)| {
            values.resize(n, None);
            Channel {
                name: model.dofs[dof].name.clone(),
                dof,
                values,
            }
        })
        .collect();
    Measured::from_samples(path, times, channels, &format!("topic \"{topic}\", joint"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A JointState in big-endian CDR, written by hand: stamp 3 s + 7 ns,
    /// frame "b", one joint "j" at 0.5, velocity [1.5], no effort.
    #[test]
    fn big_endian_cdr_decodes_with_alignment() {
        let mut d = vec![0u8, 0, 0, 0];
        d.extend_from_slice(&3u32.to_be_bytes());
        d.extend_from_slice(&7u32.to_be_bytes());
        d.extend_from_slice(&2u32.to_be_bytes());
        d.extend_from_slice(b"b\0");
        d.extend_from_slice(&[0, 0]); // pad to 4
        d.extend_from_slice(&1u32.to_be_bytes());
        d.extend_from_slice(&2u32.to_be_bytes());
        d.extend_from_slice(b"j\0");
        d.extend_from_slice(&[0, 0]);
        // Payload offsets: position count at 28, its double at 32 (8-aligned
        // already); velocity count at 40, padding to 48, its double; effort
        // count at 56.
        d.extend_from_slice(&1u32.to_be_bytes());
        d.extend_from_slice(&0.5f64.to_be_bytes());
        d.extend_from_slice(&1u32.to_be_bytes());
        d.extend_from_slice(&[0; 4]);
        d.extend_from_slice(&1.5f64.to_be_bytes());
        d.extend_from_slice(&0u32.to_be_bytes());
        let js = decode_cdr(&d).unwrap();
        assert_eq!(js.stamp_ns, Some(3_000_000_007));
        assert_eq!(js.name, vec!["j".to_string()]);
        assert_eq!((js.position, js.velocity), (vec![0.5], vec![1.5]));
        assert!(js.effort.is_empty());
        // An unknown encapsulation is named.
        let e = decode_cdr(&[0, 9, 0, 0, 1, 2]).unwrap_err();
        assert!(e.contains("unknown CDR encapsulation"), "{e}");
    }
}
