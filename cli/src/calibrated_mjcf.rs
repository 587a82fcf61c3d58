//! `calibrated.xml`: the calibrated scene as MJCF for MuJoCo
//! ([`sdrs::output::mjcf`]), written by `sdrs calibrate` next to
//! `calibrated.yaml` (issue 33, Deliver 6).
//!
//! Fitted effects map to MuJoCo attributes where one exists: joint damping
//! → `damping`, joint friction → `frictionloss`, armature → `armature`,
//! joint spring → `stiffness`/`springref`, payload and link mass scale →
//! the body's `inertial` (mass, centre of mass, full inertia), contact μ →
//! the geoms' sliding friction. The values are the Δt → 0 estimates
//! (`parameters` of `calibration.json`). Effects without an equivalent
//! (actuator gain and delay — the writer emits no actuators —, encoder
//! offsets, the barrier's κ and s) are listed in the XML's header comment
//! and in `report.md`.

use sdrs::calibrate::ModelWriter;
use sdrs::scene::Scene;

/// Writes `calibrated.xml` ([`ModelWriter`]).
pub struct CalibratedMjcf;

impl ModelWriter for CalibratedMjcf {
    fn write(&self, scene: &Scene) -> Result<(String, Vec<u8>, String), String> {
        let name = scene
            .source
            .file_stem()
            .map(|s| format!("{}_calibrated", s.to_string_lossy()))
            .unwrap_or_else(|| "calibrated".into());
        let missing = sdrs::output::mjcf::untranslated(scene);
        let mut xml = String::new();
        let mut md = String::from(
            "## MuJoCo model (`calibrated.xml`)\n\nThe scene with the fitted effects at their Δt → 0 values, as MJCF (`sdrs::output::mjcf`): joint damping → `damping`, joint friction → `frictionloss`, armature → `armature`, payload and link mass scale → the bodies' `inertial`, contact μ → geom `friction`.\n\n",
        );
        if missing.is_empty() {
            md.push_str("Every effect of the calibrated scene has a MuJoCo equivalent in it.\n\n");
        } else {
            xml.push_str("<!-- Effects of the calibrated scene with no MuJoCo equivalent here:\n");
            md.push_str("Effects with no MuJoCo equivalent (not in `calibrated.xml`):\n\n");
            for (e, why) in &missing {
                xml.push_str(&format!("     {e}: {why}\n"));
                md.push_str(&format!("- `{e}`: {why}\n"));
            }
            xml.push_str("-->\n");
            md.push('\n');
        }
        xml.push_str(&sdrs::output::mjcf::scene_to_mjcf(scene, &name));
        Ok(("calibrated.xml".into(), xml.into_bytes(), md))
    }
}
