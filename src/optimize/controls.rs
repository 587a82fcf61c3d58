//! The controller parameter vector `c`: the target-signal parameters of
//! selected joints (and optionally their PD gains).

use super::names::{self, NameError};
use crate::control::Controller;
use crate::diff::Gradients;
use crate::model::Model;
use nalgebra::DVector;

/// One entry of `c`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlTarget {
    Signal { channel: usize, param: usize },
    Kp { channel: usize },
    Kd { channel: usize },
}

/// The controller space (unbounded; gains are kept ≥ 0 by projection).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ControlSpace {
    pub entries: Vec<ControlTarget>,
}

impl ControlSpace {
    pub fn build(
        model: &Model,
        controller: &Controller,
        joints: &[String],
        gains: bool,
    ) -> Result<Self, NameError> {
        let mut entries = Vec::new();
        for name in joints {
            let l = names::joint(model, name)?;
            let link = &model.links[l];
            let dofs = link.dof_offset..link.dof_offset + link.ndof();
            let chans: Vec<usize> = controller
                .channels
                .iter()
                .enumerate()
                .filter(|(_, c)| dofs.contains(&c.dof))
                .map(|(i, _)| i)
                .collect();
            if chans.is_empty() {
                return Err(NameError {
                    what: "joint",
                    name: name.clone(),
                    msg: "has no controller target to optimize".into(),
                });
            }
            for ch in chans {
                for param in 0..controller.channels[ch].signal.nparams() {
                    entries.push(ControlTarget::Signal { channel: ch, param });
                }
                if gains {
                    entries.push(ControlTarget::Kp { channel: ch });
                    entries.push(ControlTarget::Kd { channel: ch });
                }
            }
        }
        Ok(ControlSpace { entries })
    }

    /// A name per entry: `robot/joint[:k].signal-parameter`, `….kp`, `….kd`
    /// (coordinate suffix `:k` for joints of several coordinates).
    pub fn names(&self, model: &Model, controller: &Controller) -> Vec<String> {
        let dof_name = |dof: usize| {
            model
                .links
                .iter()
                .find(|l| (l.dof_offset..l.dof_offset + l.ndof()).contains(&dof))
                .map_or(format!("dof{dof}"), |l| {
                    let base = format!("{}/{}", model.robots[l.robot].name, l.joint_name);
                    if l.ndof() > 1 {
                        format!("{base}:{}", dof - l.dof_offset)
                    } else {
                        base
                    }
                })
        };
        self.entries
            .iter()
            .map(|e| match *e {
                ControlTarget::Signal { channel, param } => {
                    let ch = &controller.channels[channel];
                    let p = ch.signal.param_names().get(param).cloned();
                    format!("{}.{}", dof_name(ch.dof), p.unwrap_or(format!("p{param}")))
                }
                ControlTarget::Kp { channel } => {
                    format!("{}.kp", dof_name(controller.channels[channel].dof))
                }
                ControlTarget::Kd { channel } => {
                    format!("{}.kd", dof_name(controller.channels[channel].dof))
                }
            })
            .collect()
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn values(&self, c: &Controller) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.entries.iter().map(|e| match *e {
                ControlTarget::Signal { channel, param } => {
                    c.channels[channel].signal.params()[param]
                }
                ControlTarget::Kp { channel } => c.channels[channel].kp,
                ControlTarget::Kd { channel } => c.channels[channel].kd,
            }),
        )
    }

    pub fn apply(&self, c: &mut Controller, x: &DVector<f64>) {
        for (e, &v) in self.entries.iter().zip(x.iter()) {
            match *e {
                ControlTarget::Signal { channel, param } => {
                    let sig = &mut c.channels[channel].signal;
                    let mut p = sig.params();
                    p[param] = v;
                    sig.set_params(&p);
                }
                ControlTarget::Kp { channel } => c.channels[channel].kp = v.max(0.0),
                ControlTarget::Kd { channel } => c.channels[channel].kd = v.max(0.0),
            }
        }
    }

    pub fn gradient(&self, g: &Gradients) -> DVector<f64> {
        DVector::from_iterator(
            self.len(),
            self.entries.iter().map(|e| match *e {
                ControlTarget::Signal { channel, param } => g.channels[channel].signal[param],
                ControlTarget::Kp { channel } => g.channels[channel].kp,
                ControlTarget::Kd { channel } => g.channels[channel].kd,
            }),
        )
    }
}
