"""`sdrs.calibrate` on a robot log written by the reference MCAP writer
(the `mcap` package, not this project's reader's own crate): `topic` picks
the JointState topic among others, `rename` maps the log's joint names to
the scene's coordinates (and drops one), and the result equals the
calibration of the same samples given as CSV. Naming the contact model's
resolution as an effect while fitting it as a setting is a clear error.

Tolerances chosen before the first run (2026-11-28): the hidden damping
within 5 %; the MCAP and CSV fits within 1e-6 relative (the log's times
are integer nanoseconds, the CSV's decimal seconds)."""

from __future__ import annotations

import json

import pytest
from mcap.writer import Writer

import sdrs

DAMPING = 0.05
# The log's joint names → the scene's coordinates (arm2's CSV columns);
# "gripper" is in the log but not in the scene: ignored by an empty rename.
RENAME = {"shoulder_joint": "shoulder", "elbow_joint": "elbow", "gripper": ""}


def _samples(root, tmp_path):
    """arm2 with a hidden joint damping, every 10th step: (header, rows)."""
    hidden = tmp_path / "hidden.yaml"
    hidden.write_text((root / "robots/calibrate/arm2.yaml").read_text()
                      + f"effects:\n  - {{effect: joint_damping, on: all, values: [{DAMPING}]}}\n")
    lines = sdrs.Scene.load(hidden).simulate(600, poses=False).to_csv().splitlines()
    header = lines[0].split(",")
    rows = [[float(x) for x in line.split(",")] for line in lines[1::10]]
    return header, rows


def _write_mcap(path, header, rows):
    """JSON-encoded sensor_msgs/msg/JointState on /robot/joint_states, and a
    decoy on the default topic /joint_states (all zeros)."""
    names = {v: k for k, v in RENAME.items() if v}
    coords = [c for c in header[1:] if c in names]
    assert len(coords) == 2, header
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="sdrs-test")
        schema = w.register_schema(name="sensor_msgs/msg/JointState", encoding="jsonschema",
                                   data=json.dumps({"type": "object"}).encode())
        real = w.register_channel(topic="/robot/joint_states", message_encoding="json", schema_id=schema)
        decoy = w.register_channel(topic="/joint_states", message_encoding="json", schema_id=schema)
        for i, row in enumerate(rows):
            ns = round(row[0] * 1e9)
            pos = [row[header.index(c)] for c in coords]
            msg = {"header": {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}},
                   "name": [names[c] for c in coords] + ["gripper"],
                   "position": pos + [0.01], "velocity": [], "effort": []}
            w.add_message(channel_id=real, log_time=ns, publish_time=ns, sequence=i,
                          data=json.dumps(msg).encode())
            zero = dict(msg, position=[0.0] * 3)
            w.add_message(channel_id=decoy, log_time=ns, publish_time=ns, sequence=i,
                          data=json.dumps(zero).encode())
        w.finish()


def test_mcap_log_with_topic_and_rename_equals_csv(root, tmp_path):
    scene = root / "robots/calibrate/arm2.yaml"
    header, rows = _samples(root, tmp_path)
    csv = tmp_path / "measured.csv"
    csv.write_text("\n".join([",".join(header)] + [",".join(repr(x) for x in r) for r in rows]) + "\n")
    log = tmp_path / "run.mcap"
    _write_mcap(log, header, rows)
    effects = ["joint_damping", "armature"]
    from_log = sdrs.calibrate(scene, log, tmp_path / "log", effects=effects,
                              topic="/robot/joint_states", rename=RENAME)
    from_csv = sdrs.calibrate(scene, csv, tmp_path / "csv", effects=effects)
    assert from_log["effect"] == "joint_damping", from_log["reason"]
    (value,) = from_log["parameters"].values()
    assert abs(value - DAMPING) <= 0.05 * DAMPING, from_log["parameters"]
    assert from_csv["candidate"] == from_log["candidate"]
    for k, v in from_csv["parameters"].items():
        assert abs(from_log["parameters"][k] - v) <= 1e-6 * abs(v), (k, v, from_log["parameters"][k])
    # Without `rename` the log's names match no coordinate; the default
    # topic is the decoy, whose zeros the arm never holds.
    with pytest.raises(sdrs.SdrsError, match="shoulder_joint"):
        sdrs.calibrate(scene, log, tmp_path / "norename", effects=effects, topic="/robot/joint_states")
    decoy = sdrs.calibrate(scene, log, tmp_path / "decoy", effects=effects, rename=RENAME)
    assert decoy["gap_before"]["overall"] > 10 * from_log["gap_before"]["overall"]


def test_contact_resolution_named_as_effect_is_an_error(root, tmp_path):
    scene = root / "robots/calibrate/slider_contact.yaml"
    with pytest.raises(sdrs.SdrsError, match="fit_contact_resolution=False"):
        sdrs.calibrate(scene, tmp_path / "unused.csv", tmp_path / "out", effects=["contact_s"],
                       fit_contact_resolution=True)
