//! Newton statistics of a scene's steps under the IPC baseline, with the
//! scene's `contact.ipc.hessian` (exact by default) or with
//! `HESSIAN=projected|exact` overriding it (see
//! `notes/ipc-baseline-newton-hessian.md`). The scene is switched to IPC as `--contact ipc`
//! does (adaptive κ unless it is an IPC scene). `MAXIT=n` overrides the
//! scene's Newton iteration cap. Prints every step that took more than
//! `MIN_ITERS` iterations, then the totals and the wall time.
//!
//! `cargo run --release -p sdrs-ipc --example step_probe -- SCENE STEPS [MIN_ITERS]`
use sdrs::scene::schema::ContactModelKind;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut scene = sdrs::scene::Scene::load(&args[1]).expect("scene");
    let steps: usize = args[2].parse().unwrap();
    let min: usize = args.get(3).map_or(20, |s| s.parse().unwrap());
    if let Some(c) = scene.contact.as_mut() {
        if c.model != ContactModelKind::Ipc {
            c.kappa_given = false;
        }
        c.model = ContactModelKind::Ipc;
        if let Ok(h) = std::env::var("HESSIAN") {
            let mut ipc = sdrs_ipc::settings::IpcSettings::of(c).expect("contact.ipc");
            ipc.hessian = match h.as_str() {
                "projected" => sdrs_ipc::settings::HessianKind::Projected,
                "exact" => sdrs_ipc::settings::HessianKind::Exact,
                other => panic!("HESSIAN={other}: projected or exact"),
            };
            ipc.store(c).expect("contact.ipc");
        }
    }
    if let Some(n) = std::env::var("MAXIT").ok().and_then(|s| s.parse().ok()) {
        scene.settings.newton.max_iters = n;
    }
    let mut sim = scene
        .simulator_with(&sdrs_ipc::IpcFactory::default())
        .expect("simulator");
    let (mut total, mut max, mut done, mut merit) = (0usize, 0usize, 0usize, 0usize);
    let t0 = std::time::Instant::now();
    for _ in 0..steps {
        match sim.step() {
            Ok(d) => {
                let n = d.newton;
                total += n.iters;
                merit += n.gradient_merit_steps;
                max = max.max(n.iters);
                done += 1;
                if n.iters > min {
                    println!(
                        "step {}: iters {} backtracks {} ccd_cuts {} merit {} grad {:.3e} floor {:.3e} value {:.6e} pairs {} min_d {:.3e}",
                        sim.state.step,
                        n.iters,
                        n.backtracks,
                        n.ccd_cuts,
                        n.gradient_merit_steps,
                        n.grad_inf,
                        n.grad_floor,
                        n.value,
                        d.contact_pairs,
                        d.min_distance
                    );
                }
            }
            Err(e) => {
                println!("FAILED: {e}");
                break;
            }
        }
    }
    println!(
        "steps {done}: Newton iterations total {total} (merit {merit}), max {max}; {:.2} s",
        t0.elapsed().as_secs_f64()
    );
}
