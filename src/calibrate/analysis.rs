//! Where simulation and measurement disagree: residuals per channel over
//! time, per regime, the windows where the error concentrates, and the
//! residual's correlation with velocity sign, velocity and acceleration.
//!
//! Regimes of a sample, per channel (from the simulated trajectory at the
//! sample time, central differences with step 2Δt): *contact* when any
//! contact pair is active, else *free*; *moving* when `|θ̇| > 5 %` of the
//! channel's largest `|θ̇|`, else *at rest*; *accelerating* when
//! `θ̇·θ̈ > 0`, else *braking* (moving samples only).

use super::data::Measured;
use super::problem::Simulated;
use serde::Serialize;

/// RMS error and sample count of one subset.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Rms {
    pub rms: f64,
    pub samples: usize,
}

impl Rms {
    fn from(sum: f64, n: usize) -> Rms {
        Rms {
            rms: if n > 0 { (sum / n as f64).sqrt() } else { 0.0 },
            samples: n,
        }
    }
}

/// Residual statistics of one channel against one simulation.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelResiduals {
    pub channel: String,
    pub all: Rms,
    pub train: Rms,
    pub holdout: Rms,
    pub free: Rms,
    pub contact: Rms,
    pub moving: Rms,
    pub at_rest: Rms,
    pub accelerating: Rms,
    pub braking: Rms,
    /// Pearson correlation of the residual with `sign θ̇`, `θ̇`, `θ̈`.
    pub corr_velocity_sign: f64,
    pub corr_velocity: f64,
    pub corr_acceleration: f64,
}

/// A time window and its share of the total squared error.
#[derive(Clone, Debug, Serialize)]
pub struct Window {
    pub t_start: f64,
    pub t_end: f64,
    pub rms: f64,
    /// Fraction of the whole trajectory's squared error in this window.
    pub share: f64,
}

/// Residual analysis against one simulation.
#[derive(Clone, Debug, Serialize)]
pub struct Analysis {
    pub channels: Vec<ChannelResiduals>,
    /// The three windows (of ten equal ones) with the largest error.
    pub worst_windows: Vec<Window>,
}

fn corr(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    if x.len() < 2 {
        return 0.0;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        0.0
    } else {
        sxy / (sxx * syy).sqrt()
    }
}

/// Analyses `sim` against `m`, with held-out samples from `split` on.
pub fn analyse(m: &Measured, sim: &Simulated, split: usize) -> Analysis {
    let nw = 10;
    let t_end = m.duration().max(1e-12);
    let mut win = vec![0.0; nw];
    let mut win_n = vec![0usize; nw];
    let mut channels = Vec::new();
    for ch in &m.channels {
        let mut acc = [(0.0, 0usize); 9];
        let (mut rs, mut sg, mut vs, mut as_) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let vmax = m
            .times
            .iter()
            .map(|&t| sim.rates(ch.dof, t).0.abs())
            .fold(0.0, f64::max);
        for (i, &t) in m.times.iter().enumerate() {
            let Some(y) = ch.values[i] else { continue };
            let r = sim.at(ch.dof, t) - y;
            let r2 = r * r;
            let (v, a) = sim.rates(ch.dof, t);
            let moving = v.abs() > 0.05 * vmax;
            let mut add = |k: usize| {
                acc[k].0 += r2;
                acc[k].1 += 1;
            };
            add(0);
            add(if i < split { 1 } else { 2 });
            add(if sim.in_contact(t) { 4 } else { 3 });
            add(if moving { 5 } else { 6 });
            if moving {
                add(if v * a > 0.0 { 7 } else { 8 });
            }
            let w = ((t / t_end * nw as f64) as usize).min(nw - 1);
            win[w] += r2;
            win_n[w] += 1;
            rs.push(r);
            sg.push(v.signum() * f64::from(moving));
            vs.push(v);
            as_.push(a);
        }
        let r = |k: usize| Rms::from(acc[k].0, acc[k].1);
        channels.push(ChannelResiduals {
            channel: ch.name.clone(),
            all: r(0),
            train: r(1),
            holdout: r(2),
            free: r(3),
            contact: r(4),
            moving: r(5),
            at_rest: r(6),
            accelerating: r(7),
            braking: r(8),
            corr_velocity_sign: corr(&rs, &sg),
            corr_velocity: corr(&rs, &vs),
            corr_acceleration: corr(&rs, &as_),
        });
    }
    let total: f64 = win.iter().sum::<f64>().max(1e-300);
    let mut windows: Vec<Window> = (0..nw)
        .map(|w| Window {
            t_start: w as f64 * t_end / nw as f64,
            t_end: (w + 1) as f64 * t_end / nw as f64,
            rms: Rms::from(win[w], win_n[w]).rms,
            share: win[w] / total,
        })
        .collect();
    windows.sort_by(|a, b| {
        b.share
            .total_cmp(&a.share)
            .then(a.t_start.total_cmp(&b.t_start))
    });
    windows.truncate(3);
    Analysis {
        channels,
        worst_windows: windows,
    }
}
