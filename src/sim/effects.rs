//! Installing calibration effects ([`crate::energy::effects`]) into a
//! simulator: their energy terms join the step objective (an actuator
//! deadband's term sits next to the PD term), actuator gains scale the
//! controller channels and actuation delays shift their targets.

use super::Simulator;
use crate::energy::Energy;
use crate::energy::effects::extra_mass::{ExtraMass, ExtraMassKind};
use crate::energy::effects::{
    Effect, EffectKind, JointCoeffs, Target, armature, coulomb, damping, deadband, delay, gain,
    spring, stribeck,
};
use nalgebra::Vector3;

/// Installs the dynamic effects into a simulator: energy terms and scaled
/// controller gains. (Contact effects are applied to the settings before
/// the contact terms are built, [`crate::scene::contact_settings`]; offsets are
/// measurement-side.)
pub fn install(effects: &[Effect], sim: &mut Simulator) {
    for e in effects {
        let v = e.values[0];
        let term: Option<Box<dyn Energy>> = match (&e.target, e.kind) {
            (Target::Dofs(d), EffectKind::JointDamping) => Some(Box::new(damping::JointDamping(
                JointCoeffs::shared(d, v, e.slot),
            ))),
            (Target::Dofs(d), EffectKind::JointFriction) => {
                Some(Box::new(coulomb::JointFriction {
                    coeffs: JointCoeffs::shared(d, v, e.slot),
                    eps: e.eps,
                }))
            }
            (Target::Dofs(d), EffectKind::StribeckFriction) => {
                Some(Box::new(stribeck::StribeckFriction {
                    coulomb: JointCoeffs::shared(d, v, e.slot),
                    excess: JointCoeffs::shared(d, e.values[1], e.slot + 1),
                    vs: stribeck::DEFAULT_VS,
                    eps: e.eps,
                }))
            }
            (Target::Dofs(d), EffectKind::ActuatorDeadband) => {
                Some(Box::new(deadband::ActuatorDeadband {
                    coeffs: JointCoeffs::shared(d, v, e.slot),
                    width: deadband::DEFAULT_WIDTH,
                }))
            }
            (Target::Dofs(d), EffectKind::Armature) => Some(Box::new(armature::Armature(
                JointCoeffs::shared(d, v, e.slot),
            ))),
            (Target::Dofs(d), EffectKind::JointSpring) => Some(Box::new(spring::JointSpring {
                coeffs: JointCoeffs::shared(d, v, e.slot),
                rest: e.values[1],
            })),
            (Target::Dofs(d), EffectKind::ActuatorGain) => {
                gain::apply(&mut sim.controller, d, v);
                None
            }
            (Target::Dofs(d), EffectKind::ActuationDelay) => {
                delay::apply(&mut sim.controller, d, v);
                None
            }
            (Target::Links(l), EffectKind::Payload) => Some(Box::new(ExtraMass {
                link: l[0],
                kind: ExtraMassKind::Payload {
                    mass: v,
                    point: Vector3::new(e.values[1], e.values[2], e.values[3]),
                },
                slot: Some(e.slot),
            })),
            (Target::Links(l), EffectKind::LinkMassScale) => {
                for &i in l {
                    sim.energies.push(Box::new(ExtraMass {
                        link: i,
                        kind: ExtraMassKind::Scale { scale: v },
                        slot: Some(e.slot),
                    }));
                }
                None
            }
            _ => None,
        };
        if let Some(t) = term {
            sim.energies.push(t);
        }
    }
}
