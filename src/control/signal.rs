//! Target signals of one coordinate.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Problems with a signal's parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalError {
    #[error("`times` and `values` must have the same length (got {0} and {1})")]
    LengthMismatch(usize, usize),
    #[error("needs at least {min} knots, got {got}")]
    TooFewKnots { min: usize, got: usize },
    #[error("`times` must be strictly increasing (at index {0})")]
    NotIncreasing(usize),
    #[error("a parameter is not finite")]
    NonFinite,
}

/// One sine term `A sin(2π f t + φ)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SineTerm {
    /// Amplitude (rad or m).
    pub amplitude: f64,
    /// Frequency (Hz).
    pub frequency: f64,
    /// Phase (rad). Default 0.
    #[serde(default)]
    pub phase: f64,
}

/// A target signal. Its velocity target is its exact time derivative.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Signal {
    /// `θ* = value`, `θ̇* = 0`.
    Constant {
        /// The target (rad or m).
        value: f64,
    },
    /// `θ* = offset + Σ A_j sin(2π f_j t + φ_j)` (the paper's spider gait).
    Sine {
        /// Constant part (rad or m). Default 0.
        #[serde(default)]
        offset: f64,
        /// The sine terms.
        terms: Vec<SineTerm>,
    },
    /// Natural cubic spline through `(times, values)`, held constant (with
    /// zero velocity) outside the knot range (the paper's chain controller
    /// uses 4 knots).
    Spline {
        /// Knot times (s), increasing.
        times: Vec<f64>,
        /// Values at the knots (rad or m).
        values: Vec<f64>,
    },
    /// Piecewise-linear interpolation of a table, held outside its range.
    Table {
        /// Sample times (s), increasing.
        times: Vec<f64>,
        /// Values at the samples (rad or m).
        values: Vec<f64>,
    },
}

impl Signal {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SignalError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            Signal::Constant { value } => finite(&[*value])
                .then_some(())
                .ok_or(SignalError::NonFinite),
            Signal::Sine { offset, terms } => {
                let ok = offset.is_finite()
                    && terms
                        .iter()
                        .all(|t| finite(&[t.amplitude, t.frequency, t.phase]));
                ok.then_some(()).ok_or(SignalError::NonFinite)
            }
            Signal::Spline { times, values } | Signal::Table { times, values } => {
                let min = if matches!(self, Signal::Spline { .. }) {
                    2
                } else {
                    1
                };
                if times.len() != values.len() {
                    return Err(SignalError::LengthMismatch(times.len(), values.len()));
                }
                if times.len() < min {
                    return Err(SignalError::TooFewKnots {
                        min,
                        got: times.len(),
                    });
                }
                if !finite(times) || !finite(values) {
                    return Err(SignalError::NonFinite);
                }
                if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
                    return Err(SignalError::NotIncreasing(i + 1));
                }
                Ok(())
            }
        }
    }

    /// `(θ*(t), θ̇*(t))`.
    pub fn eval(&self, t: f64) -> (f64, f64) {
        match self {
            Signal::Constant { value } => (*value, 0.0),
            Signal::Sine { offset, terms } => terms.iter().fold((*offset, 0.0), |(v, d), term| {
                let w = TAU * term.frequency;
                let arg = w * t + term.phase;
                (
                    v + term.amplitude * arg.sin(),
                    d + term.amplitude * w * arg.cos(),
                )
            }),
            Signal::Table { times, values } => {
                if times.len() == 1 || t <= times[0] {
                    return (values[0], 0.0);
                }
                let last = times.len() - 1;
                if t >= times[last] {
                    return (values[last], 0.0);
                }
                let i = times.partition_point(|&x| x <= t) - 1;
                let slope = (values[i + 1] - values[i]) / (times[i + 1] - times[i]);
                (values[i] + slope * (t - times[i]), slope)
            }
            Signal::Spline { times, values } => natural_spline_eval(times, values, t),
        }
    }
}

impl Signal {
    /// `θ̈*(t)`: the second time derivative (sine: `−Σ A_j ω_j² sin(ω_j t + φ_j)`;
    /// spline: its moment interpolated linearly; constant, table, and outside
    /// a spline's knots: 0 — a table's velocity jumps at its knots are not
    /// represented).
    pub fn accel(&self, t: f64) -> f64 {
        match self {
            Signal::Constant { .. } | Signal::Table { .. } => 0.0,
            Signal::Sine { terms, .. } => terms
                .iter()
                .map(|term| {
                    let w = TAU * term.frequency;
                    -term.amplitude * w * w * (w * t + term.phase).sin()
                })
                .sum(),
            Signal::Spline { times, values } => {
                let n = times.len();
                if t <= times[0] || t >= times[n - 1] {
                    return 0.0;
                }
                let m = natural_spline_moments(times, values);
                let i = times.partition_point(|&v| v <= t) - 1;
                let h = times[i + 1] - times[i];
                ((times[i + 1] - t) * m[i] + (t - times[i]) * m[i + 1]) / h
            }
        }
    }

    /// Number of learnable parameters: constant `[value]`; sine `[offset,
    /// (amplitude, frequency, phase) per term]`; spline and table: the knot
    /// values (knot times are fixed).
    pub fn nparams(&self) -> usize {
        match self {
            Signal::Constant { .. } => 1,
            Signal::Sine { terms, .. } => 1 + 3 * terms.len(),
            Signal::Spline { values, .. } | Signal::Table { values, .. } => values.len(),
        }
    }

    /// A name per parameter, in the order of [`Signal::nparams`]
    /// (`value`; `offset`, `term0.amplitude`, `term0.frequency`,
    /// `term0.phase`, …; `values[k]` at `times[k]`).
    pub fn param_names(&self) -> Vec<String> {
        match self {
            Signal::Constant { .. } => vec!["value".into()],
            Signal::Sine { terms, .. } => {
                let mut v = vec!["offset".to_string()];
                for k in 0..terms.len() {
                    for f in ["amplitude", "frequency", "phase"] {
                        v.push(format!("term{k}.{f}"));
                    }
                }
                v
            }
            Signal::Spline { times, .. } | Signal::Table { times, .. } => times
                .iter()
                .enumerate()
                .map(|(k, t)| format!("values[{k}] (t = {t} s)"))
                .collect(),
        }
    }

    /// The parameters, in the order of [`Signal::nparams`].
    pub fn params(&self) -> Vec<f64> {
        match self {
            Signal::Constant { value } => vec![*value],
            Signal::Sine { offset, terms } => {
                let mut v = vec![*offset];
                for t in terms {
                    v.extend([t.amplitude, t.frequency, t.phase]);
                }
                v
            }
            Signal::Spline { values, .. } | Signal::Table { values, .. } => values.clone(),
        }
    }

    /// Sets the parameters (same order and length as [`Signal::params`]).
    pub fn set_params(&mut self, p: &[f64]) {
        assert_eq!(p.len(), self.nparams(), "parameter count");
        match self {
            Signal::Constant { value } => *value = p[0],
            Signal::Sine { offset, terms } => {
                *offset = p[0];
                for (k, t) in terms.iter_mut().enumerate() {
                    t.amplitude = p[1 + 3 * k];
                    t.frequency = p[2 + 3 * k];
                    t.phase = p[3 + 3 * k];
                }
            }
            Signal::Spline { values, .. } | Signal::Table { values, .. } => {
                values.copy_from_slice(p)
            }
        }
    }

    /// `(∂θ*(t)/∂c, ∂θ̇*(t)/∂c)` for the parameters `c`.
    pub fn param_grad(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        match self {
            Signal::Constant { .. } => (vec![1.0], vec![0.0]),
            Signal::Sine { terms, .. } => {
                let (mut dv, mut dd) = (vec![1.0], vec![0.0]);
                for term in terms {
                    let w = TAU * term.frequency;
                    let arg = w * t + term.phase;
                    let (s, c) = arg.sin_cos();
                    // value A sin(arg), derivative A w cos(arg)
                    dv.extend([s, term.amplitude * c * TAU * t, term.amplitude * c]);
                    dd.extend([
                        w * c,
                        term.amplitude * TAU * c - term.amplitude * w * s * TAU * t,
                        -term.amplitude * w * s,
                    ]);
                }
                (dv, dd)
            }
            // Both interpolants are linear in the knot values: evaluate the
            // cardinal basis.
            Signal::Spline { values, .. } | Signal::Table { values, .. } => {
                let mut unit = self.clone();
                let n = values.len();
                let (mut dv, mut dd) = (vec![0.0; n], vec![0.0; n]);
                for k in 0..n {
                    let mut e = vec![0.0; n];
                    e[k] = 1.0;
                    unit.set_params(&e);
                    let (v, d) = unit.eval(t);
                    dv[k] = v;
                    dd[k] = d;
                }
                (dv, dd)
            }
        }
    }
}

/// Second derivatives `M_i` of the natural cubic spline through the knots
/// (tridiagonal solve, `M_0 = M_n = 0`).
fn natural_spline_moments(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut m = vec![0.0; n];
    if n < 3 {
        return m;
    }
    let mut c = vec![0.0; n];
    let mut d = vec![0.0; n];
    for i in 1..n - 1 {
        let h0 = x[i] - x[i - 1];
        let h1 = x[i + 1] - x[i];
        let a = h0 / 6.0;
        let b = (h0 + h1) / 3.0;
        let cc = h1 / 6.0;
        let rhs = (y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0;
        let denom = b - a * c[i - 1];
        c[i] = cc / denom;
        d[i] = (rhs - a * d[i - 1]) / denom;
    }
    for i in (1..n - 1).rev() {
        m[i] = d[i] - c[i] * m[i + 1];
    }
    m
}

fn natural_spline_eval(x: &[f64], y: &[f64], t: f64) -> (f64, f64) {
    let n = x.len();
    if t <= x[0] {
        return (y[0], 0.0);
    }
    if t >= x[n - 1] {
        return (y[n - 1], 0.0);
    }
    let m = natural_spline_moments(x, y);
    let i = x.partition_point(|&v| v <= t) - 1;
    let h = x[i + 1] - x[i];
    let a = (x[i + 1] - t) / h;
    let b = (t - x[i]) / h;
    let v = a * y[i]
        + b * y[i + 1]
        + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * h * h / 6.0;
    let dv = (y[i + 1] - y[i]) / h
        + (-(3.0 * a * a - 1.0) * m[i] + (3.0 * b * b - 1.0) * m[i + 1]) * h / 6.0;
    (v, dv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check(s: &Signal, ts: &[f64]) {
        for &t in ts {
            let h = 1e-6;
            let fd = (s.eval(t + h).0 - s.eval(t - h).0) / (2.0 * h);
            assert!(
                (fd - s.eval(t).1).abs() < 1e-6,
                "{s:?} at {t}: fd {fd} vs {}",
                s.eval(t).1
            );
        }
    }

    #[test]
    fn velocity_targets_are_time_derivatives() {
        let sine = Signal::Sine {
            offset: 0.1,
            terms: vec![SineTerm {
                amplitude: 0.5,
                frequency: 2.0,
                phase: 0.3,
            }],
        };
        fd_check(&sine, &[0.0, 0.13, 0.77]);
        let spline = Signal::Spline {
            times: vec![0.0, 1.0, 2.0, 3.0],
            values: vec![0.0, 1.0, -0.5, 0.2],
        };
        spline.validate().unwrap();
        fd_check(&spline, &[0.2, 0.9, 1.5, 2.7]);
        let table = Signal::Table {
            times: vec![0.0, 1.0],
            values: vec![1.0, 3.0],
        };
        fd_check(&table, &[0.5]);
    }

    #[test]
    fn signal_parameter_gradients_match_finite_differences() {
        let signals = [
            Signal::Constant { value: 0.3 },
            Signal::Sine {
                offset: 0.1,
                terms: vec![
                    SineTerm {
                        amplitude: 0.5,
                        frequency: 2.0,
                        phase: 0.3,
                    },
                    SineTerm {
                        amplitude: -0.2,
                        frequency: 0.7,
                        phase: 1.1,
                    },
                ],
            },
            Signal::Spline {
                times: vec![0.0, 1.0, 2.0, 3.0],
                values: vec![0.0, 1.0, -0.5, 0.2],
            },
            Signal::Table {
                times: vec![0.0, 1.0, 2.5],
                values: vec![1.0, 3.0, 2.0],
            },
        ];
        for s in &signals {
            for t in [0.37, 1.3, 2.2] {
                let (dv, dd) = s.param_grad(t);
                let p = s.params();
                for k in 0..p.len() {
                    let h = 1e-6;
                    let (mut a, mut b) = (s.clone(), s.clone());
                    let (mut pa, mut pb) = (p.clone(), p.clone());
                    pa[k] += h;
                    pb[k] -= h;
                    a.set_params(&pa);
                    b.set_params(&pb);
                    let fv = (a.eval(t).0 - b.eval(t).0) / (2.0 * h);
                    let fd = (a.eval(t).1 - b.eval(t).1) / (2.0 * h);
                    assert!((fv - dv[k]).abs() < 1e-6, "{s:?} value param {k} at {t}");
                    assert!(
                        (fd - dd[k]).abs() < 1e-5,
                        "{s:?} velocity param {k} at {t}: {fd} vs {}",
                        dd[k]
                    );
                }
            }
        }
    }

    #[test]
    fn spline_interpolates_knots() {
        let times = vec![0.0, 0.5, 1.7, 3.0];
        let values = vec![0.3, -1.0, 2.0, 0.5];
        let s = Signal::Spline {
            times: times.clone(),
            values: values.clone(),
        };
        for (t, v) in times.iter().zip(&values) {
            assert!((s.eval(*t).0 - v).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_signals_are_rejected() {
        let s = Signal::Spline {
            times: vec![0.0, 0.0],
            values: vec![1.0, 2.0],
        };
        assert_eq!(s.validate(), Err(SignalError::NotIncreasing(1)));
        let s = Signal::Table {
            times: vec![0.0],
            values: vec![],
        };
        assert_eq!(s.validate(), Err(SignalError::LengthMismatch(1, 0)));
    }
}
