//! `sdrs calibrate --measured log.mcap`: robot logs in MCAP
//! (`sensor_msgs/msg/JointState`, CDR and JSON) read as measured data.
//! The same samples as CSV and as MCAP give the same `Measured` bit for
//! bit (every chunk compression) and the same `calibration.json`; every
//! bad log is a typed error naming the file, the topic and the message,
//! and nothing is written on error. Files are written here with the
//! `mcap` crate's writer and a small CDR encoder: no Python needed.

use crate::common;

use mcap::records::MessageHeader;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sdrs::calibrate::data::Measured;
use sdrs::calibrate::mcap_log::{self, LogMapping};
use sdrs::calibrate::{CalibrateError, CalibrateOptions, run};
use sdrs::energy::effects::EffectKind;
use sdrs::scene::Scene;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A wall-clock epoch offset as real logs have (ns).
const EPOCH: i128 = 1_764_000_000_123_456_789;

fn scene_path() -> PathBuf {
    common::robots("calibrate/arm2.yaml")
}

/// One sample: nanoseconds after the first, values of `shoulder`, `elbow`.
type Sample = (i128, Vec<f64>);

/// The arm with a hidden Coulomb friction, sampled at 100 Hz ± 3 ms of
/// jitter (integer nanoseconds), with a gap, plus seeded noise of 1e-4.
fn samples() -> Vec<Sample> {
    let text = std::fs::read_to_string(scene_path()).unwrap();
    let text =
        format!("{text}\neffects:\n  - {{effect: joint_friction, on: all, values: [0.4]}}\n");
    let sc = Scene::from_str(&text, Path::new("hidden.yaml")).unwrap();
    let dt = sc.settings.dt;
    let traj = sdrs::sim::run::run(&mut sc.simulator(), 610, |_| {}).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut out = Vec::new();
    for i in 0..=120i128 {
        let jitter: i128 = if i == 0 {
            0
        } else {
            rng.random_range(-3_000_000..3_000_000)
        };
        let ns = i * 10_000_000 + jitter;
        if (410_000_000..470_000_000).contains(&ns) {
            continue;
        }
        let t = ns as f64 / 1e9;
        let v = (0..2)
            .map(|k| {
                let g: f64 = rng.random_range(-1.0..1.0);
                sdrs::calibrate::data::interpolate(&traj.states, dt, k, t) + 1e-4 * g
            })
            .collect();
        out.push((ns, v));
    }
    out
}

/// The samples as the CSV `sdrs calibrate` reads (times in s, printed
/// shortest-round-trip: they parse back to `ns / 1e9` exactly).
fn csv(s: &[Sample]) -> String {
    let mut out = String::from("t,shoulder,elbow\n");
    for (ns, v) in s {
        out.push_str(&format!("{},{},{}\n", *ns as f64 / 1e9, v[0], v[1]));
    }
    out
}

/// A CDR (little-endian) encoder with alignment relative to the payload.
struct CdrOut(Vec<u8>);

impl CdrOut {
    fn new() -> Self {
        CdrOut(vec![0, 1, 0, 0])
    }
    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u32(&mut self, x: u32) {
        self.align(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }
    fn f64s(&mut self, v: &[f64]) {
        self.u32(v.len() as u32);
        for x in v {
            self.align(8);
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// A JointState message to encode.
#[derive(Clone)]
struct Js {
    stamp: Option<i128>,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
}

fn cdr(m: &Js) -> Vec<u8> {
    let mut c = CdrOut::new();
    let st = m.stamp.unwrap_or(0);
    c.u32((st / 1_000_000_000) as i32 as u32);
    c.u32((st % 1_000_000_000) as u32);
    c.string("base_link");
    c.u32(m.name.len() as u32);
    for n in &m.name {
        c.string(n);
    }
    c.f64s(&m.position);
    c.f64s(&m.velocity);
    c.f64s(&[]);
    c.0
}

fn json(m: &Js) -> Vec<u8> {
    let mut v = serde_json::json!({
        "name": m.name,
        "position": m.position,
        "velocity": m.velocity,
        "effort": [],
    });
    if let Some(st) = m.stamp {
        v["header"] = serde_json::json!({
            "stamp": {"sec": (st / 1_000_000_000) as i64, "nanosec": (st % 1_000_000_000) as i64},
            "frame_id": "base_link"
        });
    }
    serde_json::to_vec(&v).unwrap()
}

/// The samples as JointState messages (stamped `EPOCH + ns`, logged 2 ms
/// later), joints named `names`.
fn messages(s: &[Sample], names: &[&str]) -> Vec<Js> {
    s.iter()
        .map(|(ns, v)| Js {
            stamp: Some(EPOCH + ns),
            name: names.iter().map(|n| n.to_string()).collect(),
            position: v.clone(),
            velocity: vec![0.0; v.len()],
        })
        .collect()
}

#[derive(Clone, Copy)]
enum Enc {
    Cdr,
    Json,
    /// A channel whose encoding no reader knows.
    Protobuf,
}

/// Writes an MCAP file: `msgs` on `topic` in encoding `enc`, with a
/// chatter topic interleaved, chunks compressed with `compression`.
fn mcap_bytes(
    msgs: &[Js],
    topic: &str,
    enc: Enc,
    compression: Option<mcap::Compression>,
) -> Vec<u8> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new()
            .compression(compression)
            .profile("ros2")
            .create(&mut buf)
            .unwrap();
        let (schema, encoding) = match enc {
            Enc::Cdr => (
                w.add_schema("sensor_msgs/msg/JointState", "ros2msg", b"# JointState")
                    .unwrap(),
                "cdr",
            ),
            Enc::Json => (
                w.add_schema("sensor_msgs/msg/JointState", "jsonschema", b"{}")
                    .unwrap(),
                "json",
            ),
            Enc::Protobuf => (
                w.add_schema("sensor_msgs.JointState", "protobuf", b"")
                    .unwrap(),
                "protobuf",
            ),
        };
        let ch = w
            .add_channel(schema, topic, encoding, &BTreeMap::new())
            .unwrap();
        let other = w
            .add_channel(0, "/chatter", "json", &BTreeMap::new())
            .unwrap();
        for (k, m) in msgs.iter().enumerate() {
            let log_time = (m.stamp.unwrap_or(EPOCH + 10_000_000 * k as i128) + 2_000_000) as u64;
            let data = match enc {
                Enc::Cdr => cdr(m),
                Enc::Json | Enc::Protobuf => json(m),
            };
            let h = |channel_id| MessageHeader {
                channel_id,
                sequence: k as u32,
                log_time,
                publish_time: log_time,
            };
            w.write_to_known_channel(&h(ch), &data).unwrap();
            w.write_to_known_channel(&h(other), b"{\"data\": \"hi\"}")
                .unwrap();
        }
        w.finish().unwrap();
    }
    buf.into_inner()
}

fn model() -> sdrs::model::Model {
    Scene::load(scene_path()).unwrap().model
}

fn assert_same(a: &Measured, b: &Measured) {
    assert_eq!(a.times.len(), b.times.len());
    for (x, y) in a.times.iter().zip(&b.times) {
        assert_eq!(x.to_bits(), y.to_bits(), "time {x} vs {y}");
    }
    assert_eq!(a.channels.len(), b.channels.len());
    for (p, q) in a.channels.iter().zip(&b.channels) {
        assert_eq!((&p.name, p.dof), (&q.name, q.dof));
        let bits = |v: &[Option<f64>]| v.iter().map(|x| x.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&p.values), bits(&q.values), "channel {}", p.name);
    }
}

#[test]
fn mcap_samples_equal_the_csv_samples_bit_for_bit() {
    let s = samples();
    let model = model();
    let from_csv = Measured::parse(&csv(&s), Path::new("m.csv"), &model).unwrap();
    let msgs = messages(&s, &["shoulder", "elbow"]);
    let map = LogMapping::default();
    for (enc, label) in [(Enc::Cdr, "cdr"), (Enc::Json, "json")] {
        for (c, cname) in [
            (None, "uncompressed"),
            (Some(mcap::Compression::Zstd), "zstd"),
            (Some(mcap::Compression::Lz4), "lz4"),
        ] {
            let bytes = mcap_bytes(&msgs, "/joint_states", enc, c);
            let m = mcap_log::parse(&bytes, Path::new("m.mcap"), &model, &map)
                .unwrap_or_else(|e| panic!("{label}, {cname}: {e}"));
            assert_same(&from_csv, &m);
        }
    }
}

#[test]
fn another_topic_renamed_joints_ignored_joints_and_log_times() {
    let s = samples();
    let model = model();
    let from_csv = Measured::parse(&csv(&s), Path::new("m.csv"), &model).unwrap();
    // Joints named as a ROS driver names them, a gripper the scene lacks,
    // listed in another order.
    let mut msgs = messages(&s, &["arm_elbow_joint", "arm_shoulder_joint"]);
    for m in &mut msgs {
        m.position.swap(0, 1);
        m.name.push("gripper".into());
        m.position.push(0.01);
        m.velocity.push(0.0);
    }
    let map = LogMapping {
        topic: Some("/robot/joint_states".into()),
        rename: vec![
            ("arm_shoulder_joint".into(), "shoulder".into()),
            ("arm_elbow_joint".into(), "elbow".into()),
            ("gripper".into(), String::new()),
        ],
    };
    let bytes = mcap_bytes(&msgs, "/robot/joint_states", Enc::Cdr, None);
    let m = mcap_log::parse(&bytes, Path::new("m.mcap"), &model, &map).unwrap();
    assert_same(&from_csv, &m);
    // Without header stamps (JSON without `header`), the log time is the
    // clock: the same relative times (the log time is the stamp + 2 ms).
    for m in &mut msgs {
        m.stamp = m.stamp.map(|t| t + 2_000_000);
    }
    let stamped = mcap_bytes(&msgs, "/robot/joint_states", Enc::Json, None);
    let a = mcap_log::parse(&stamped, Path::new("m.mcap"), &model, &map).unwrap();
    let unstamped: Vec<Js> = msgs
        .iter()
        .map(|m| Js {
            stamp: None,
            ..m.clone()
        })
        .collect();
    // The writer logs unstamped messages at EPOCH + 10 ms·k + 2 ms: not
    // the samples' times, so compare with explicit log times instead.
    let b = mcap_log::parse(
        &mcap_bytes_logged(&unstamped, &msgs),
        Path::new("m.mcap"),
        &model,
        &map,
    )
    .unwrap();
    assert_same(&a, &b);
}

/// `msgs` (without stamps) written with the log times of `clock`'s stamps.
fn mcap_bytes_logged(msgs: &[Js], clock: &[Js]) -> Vec<u8> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let ch = w
            .add_channel(0, "/robot/joint_states", "json", &BTreeMap::new())
            .unwrap();
        for (k, (m, c)) in msgs.iter().zip(clock).enumerate() {
            let t = c.stamp.unwrap() as u64;
            let h = MessageHeader {
                channel_id: ch,
                sequence: k as u32,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&h, &json(m)).unwrap();
        }
        w.finish().unwrap();
    }
    buf.into_inner()
}

fn opts(measured: &Path, out: &Path, log: LogMapping) -> CalibrateOptions {
    CalibrateOptions {
        scene: scene_path(),
        measured: measured.to_path_buf(),
        more_measured: Vec::new(),
        out: out.to_path_buf(),
        effects: vec![EffectKind::JointDamping, EffectKind::JointFriction],
        holdout: 0.3,
        select: Default::default(),
        log,
        fit_contact_resolution: false,
    }
}

/// `calibration.json` as a value, with the recordings' paths removed (the
/// one place the input's name appears).
fn result_json(out: &Path) -> serde_json::Value {
    let mut j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("calibration.json")).unwrap()).unwrap();
    for r in j["recordings"].as_array_mut().unwrap() {
        r["path"] = serde_json::Value::Null;
    }
    j
}

#[test]
fn csv_cdr_and_json_give_the_same_calibration() {
    let dir = common::scratch_dir("calibrate-mcap-same");
    let s = samples();
    let c = dir.join("m.csv");
    std::fs::write(&c, csv(&s)).unwrap();
    run(&opts(&c, &dir.join("out_csv"), LogMapping::default())).unwrap();
    let reference = result_json(&dir.join("out_csv"));
    assert_eq!(reference["verdict"], "effect");
    assert_eq!(reference["candidate"], "joint_friction/all");
    let msgs = messages(&s, &["shoulder", "elbow"]);
    for (enc, name) in [(Enc::Cdr, "cdr"), (Enc::Json, "json")] {
        let p = dir.join(format!("m_{name}.mcap"));
        std::fs::write(
            &p,
            mcap_bytes(&msgs, "/joint_states", enc, Some(mcap::Compression::Zstd)),
        )
        .unwrap();
        let out = dir.join(format!("out_{name}"));
        run(&opts(&p, &out, LogMapping::default())).unwrap();
        assert_eq!(
            result_json(&out),
            reference,
            "{name}: calibration.json differs from the CSV's"
        );
        // Bitwise, not merely equal as numbers: the text is the same too
        // once the path is taken out.
        let text = |d: &Path, f: &str| {
            std::fs::read_to_string(d.join("calibration.json"))
                .unwrap()
                .replace(f, "MEASURED")
        };
        assert_eq!(
            text(&out, p.to_str().unwrap()),
            text(&dir.join("out_csv"), c.to_str().unwrap())
        );
    }
}

/// Runs with `bytes` as `measured.mcap`; the error and its message, after
/// checking that nothing was written and the file is named.
fn error_for(name: &str, bytes: &[u8], log: LogMapping) -> (CalibrateError, String) {
    let dir = common::scratch_dir(&format!("calibrate-mcap-bad-{name}"));
    let m = dir.join("measured.mcap");
    std::fs::write(&m, bytes).unwrap();
    let out = dir.join("out");
    let e = run(&opts(&m, &out, log)).expect_err(name);
    let msg = e.to_string();
    eprintln!("{name}: {msg}");
    assert!(!out.exists(), "{name}: output directory written on error");
    assert!(
        msg.contains("measured.mcap"),
        "{name}: the file is not named: {msg}"
    );
    (e, msg)
}

fn good_messages() -> Vec<Js> {
    messages(&samples()[..30], &["shoulder", "elbow"])
}

fn good_file() -> Vec<u8> {
    mcap_bytes(&good_messages(), "/joint_states", Enc::Cdr, None)
}

#[test]
fn truncated_file_and_bad_magic() {
    let b = good_file();
    let (e, msg) = error_for("truncated", &b[..b.len() - 40], LogMapping::default());
    assert!(matches!(e, CalibrateError::Mcap { .. }), "{e:?}");
    assert!(msg.contains("truncated"), "{msg}");
    // The reader reports after the last message it could read.
    assert!(msg.contains("after message 60 of the file"), "{msg}");
    let mut bad = b.clone();
    bad[1..5].copy_from_slice(b"MCAQ");
    let (e, msg) = error_for("magic", &bad, LogMapping::default());
    assert!(matches!(e, CalibrateError::Mcap { .. }), "{e:?}");
    assert!(
        msg.contains("bad magic") && msg.contains("before the first message"),
        "{msg}"
    );
    let (_, msg) = error_for("csv-as-mcap", b"t,shoulder\n0,1\n", LogMapping::default());
    assert!(msg.contains("bad magic"), "{msg}");
}

#[test]
fn unsupported_chunk_compression_is_named() {
    let mut b = mcap_bytes(
        &good_messages(),
        "/joint_states",
        Enc::Cdr,
        Some(mcap::Compression::Zstd),
    );
    // Rename the compression of every chunk (same length, CRCs cover the
    // uncompressed data only).
    let mut k = 0;
    while let Some(i) = b[k..].windows(4).position(|w| w == b"zstd") {
        b[k + i..k + i + 4].copy_from_slice(b"brot");
        k += i + 4;
    }
    let (e, msg) = error_for("compression", &b, LogMapping::default());
    assert!(matches!(e, CalibrateError::Mcap { .. }), "{e:?}");
    assert!(
        msg.contains("compression \"brot\" is not supported") && msg.contains("zstd and lz4"),
        "{msg}"
    );
}

#[test]
fn missing_topic_lists_the_topics_present() {
    let b = mcap_bytes(&good_messages(), "/arm/joint_states", Enc::Cdr, None);
    let (e, msg) = error_for("topic", &b, LogMapping::default());
    assert!(
        matches!(&e, CalibrateError::LogTopic { topic, .. } if topic == "/joint_states"),
        "{e:?}"
    );
    assert!(
        msg.contains("/arm/joint_states (30 messages)") && msg.contains("/chatter (30 messages)"),
        "{msg}"
    );
}

#[test]
fn unknown_encoding_and_schema_are_named() {
    let b = mcap_bytes(&good_messages(), "/joint_states", Enc::Protobuf, None);
    let (e, msg) = error_for("encoding", &b, LogMapping::default());
    assert!(matches!(e, CalibrateError::LogTopic { .. }), "{e:?}");
    assert!(
        msg.contains("topic \"/joint_states\"")
            && msg.contains("message encoding \"protobuf\" is not read"),
        "{msg}"
    );
    // CDR of another message type.
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let s = w
            .add_schema("std_msgs/msg/Float64", "ros2msg", b"")
            .unwrap();
        let ch = w
            .add_channel(s, "/joint_states", "cdr", &BTreeMap::new())
            .unwrap();
        let h = MessageHeader {
            channel_id: ch,
            sequence: 0,
            log_time: 5,
            publish_time: 5,
        };
        w.write_to_known_channel(&h, &[0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])
            .unwrap();
        w.finish().unwrap();
    }
    let (_, msg) = error_for("schema", &buf.into_inner(), LogMapping::default());
    assert!(
        msg.contains("schema \"std_msgs/msg/Float64\"")
            && msg.contains("sensor_msgs/msg/JointState"),
        "{msg}"
    );
}

/// Good messages with message `k` (0-based) changed by `f`.
fn with_message(enc: Enc, k: usize, f: impl Fn(&mut Js)) -> Vec<u8> {
    let mut m = good_messages();
    f(&mut m[k]);
    mcap_bytes(&m, "/joint_states", enc, None)
}

/// The log time the writer gives message `k` of [`good_messages`].
fn log_time(k: usize) -> u64 {
    (good_messages()[k].stamp.unwrap() + 2_000_000) as u64
}

#[test]
fn unknown_and_missing_joints() {
    let b = with_message(Enc::Cdr, 4, |m| m.name[1] = "wrist".into());
    let (e, msg) = error_for("unknown-joint", &b, LogMapping::default());
    assert!(
        matches!(e, CalibrateError::LogMessage { index: 5, .. }),
        "{e:?}"
    );
    assert!(
        msg.contains(&format!("message 5 (log time {} ns)", log_time(4)))
            && msg.contains("joint \"wrist\" is not a coordinate of the scene")
            && msg.contains("shoulder, elbow")
            && msg.contains("--rename wrist="),
        "{msg}"
    );
    let map = LogMapping {
        topic: None,
        rename: vec![("arm_wrist_joint".into(), "elbow".into())],
    };
    let (e, msg) = error_for("missing-joint", &good_file(), map);
    assert!(matches!(e, CalibrateError::LogTopic { .. }), "{e:?}");
    assert!(
        msg.contains("missing joint: \"arm_wrist_joint\"") && msg.contains("/joint_states"),
        "{msg}"
    );
}

#[test]
fn non_monotonic_time_names_the_message() {
    let b = with_message(Enc::Json, 7, |m| {
        m.stamp = m.stamp.map(|t| t - 25_000_000);
    });
    let (e, msg) = error_for("nonmono", &b, LogMapping::default());
    assert!(
        matches!(e, CalibrateError::LogMessage { index: 8, .. }),
        "{e:?}"
    );
    assert!(
        msg.contains("message 8 (log time") && msg.contains("time does not increase: header stamp"),
        "{msg}"
    );
    // A stamp dropped half way: two clocks.
    let b = with_message(Enc::Json, 3, |m| m.stamp = None);
    let (_, msg) = error_for("clocks", &b, LogMapping::default());
    assert!(
        msg.contains("message 4") && msg.contains("no header stamp"),
        "{msg}"
    );
}

#[test]
fn nan_and_short_arrays_name_the_message_and_joint() {
    let b = with_message(Enc::Cdr, 2, |m| m.position[1] = f64::NAN);
    let (e, msg) = error_for("nan", &b, LogMapping::default());
    assert!(
        matches!(e, CalibrateError::LogMessage { index: 3, .. }),
        "{e:?}"
    );
    assert!(
        msg.contains("joint \"elbow\": position[1] = NaN is not a finite number"),
        "{msg}"
    );
    let b = with_message(Enc::Cdr, 9, |m| {
        m.position.pop();
    });
    let (_, msg) = error_for("fewer", &b, LogMapping::default());
    assert!(
        msg.contains("message 10") && msg.contains("1 position(s) for 2 name(s)"),
        "{msg}"
    );
    let b = with_message(Enc::Json, 9, |m| m.velocity = vec![0.0; 3]);
    let (_, msg) = error_for("velocity", &b, LogMapping::default());
    assert!(msg.contains("3 velocity value(s) for 2 name(s)"), "{msg}");
    let b = with_message(Enc::Cdr, 9, |m| m.name[1] = "shoulder".into());
    let (_, msg) = error_for("twice", &b, LogMapping::default());
    assert!(msg.contains("joint \"shoulder\" appears twice"), "{msg}");
}

#[test]
fn undecodable_messages_name_the_field() {
    // A CDR message cut inside its position array.
    let mut m = good_messages();
    let data = cdr(&m[0]);
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let s = w
            .add_schema("sensor_msgs/msg/JointState", "ros2msg", b"")
            .unwrap();
        let ch = w
            .add_channel(s, "/joint_states", "cdr", &BTreeMap::new())
            .unwrap();
        let h = MessageHeader {
            channel_id: ch,
            sequence: 0,
            log_time: 9,
            publish_time: 9,
        };
        w.write_to_known_channel(&h, &data[..data.len() - 30])
            .unwrap();
        w.finish().unwrap();
    }
    let (e, msg) = error_for("cut-cdr", &buf.into_inner(), LogMapping::default());
    assert!(
        matches!(
            e,
            CalibrateError::LogMessage {
                index: 1,
                log_time: 9,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        msg.contains("the message ends at byte") && msg.contains("position"),
        "{msg}"
    );
    // JSON: a null position (JSON has no NaN) and a missing array.
    m[5].position[0] = f64::NAN; // serde_json writes NaN as null
    let (_, msg) = error_for(
        "null",
        &mcap_bytes(&m, "/joint_states", Enc::Json, None),
        LogMapping::default(),
    );
    assert!(
        msg.contains("message 6") && msg.contains("position[0] = null is not a number"),
        "{msg}"
    );
}
