//! One contact-potential evaluation (value + gradient + Hessian, pose space)
//! of SDRS `U_c` vs the IPC baseline on the same pair of random convex hulls
//! with 8 … 1024 vertices per hull, at half the interaction range of each
//! model (see [`sdrs_cli::potential_bench`]). `sdrs compare` runs the same
//! measurement and writes it into its report.
//!
//! Optionally writes the cases to a JSON file for the ipctk timing script
//! (`tools/bench/bench_ipctk.py`).
//!
//! Run: `cargo run --release -p sdrs-cli --example bench_potential [cases.json]`.

use sdrs::contact::ContactParams;
use sdrs_cli::potential_bench::{median, potential_cases, time_case};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1);
    let params = ContactParams::default();
    let range = params.support_distance();
    println!(
        "contact potential, value+gradient+Hessian, median µs per evaluation (4 random pairs per size)"
    );
    println!(
        "SDRS s = {}, range {range:.4} m; IPC d̂ = {range:.4} m; gap = half the range\n",
        params.s
    );
    println!(
        "{:>8} | {:>10} | {:>10} {:>8} {:>8} | {:>7}",
        "vertices", "SDRS µs", "IPC µs", "cands", "active", "IPC/SDRS"
    );
    let sizes = [8usize, 16, 32, 64, 128, 256, 512, 1024];
    let cases = potential_cases(&sizes, 4, 2024, &params)?;
    for &m in &sizes {
        let reps = (20_000 / m).clamp(20, 500);
        let (mut ts, mut ti, mut nc, mut na) = (vec![], vec![], vec![], vec![]);
        for c in cases.iter().filter(|c| c.vertices == m) {
            let t = time_case(c, &params, reps)?;
            ts.push(t.sdrs_us);
            ti.push(t.ipc_us);
            nc.push(t.candidates as f64);
            na.push(t.active as f64);
        }
        let (s, i) = (median(&mut ts), median(&mut ti));
        println!(
            "{m:>8} | {s:>10.1} | {i:>10.1} {:>8.0} {:>8.0} | {:>7.2}",
            median(&mut nc),
            median(&mut na),
            i / s
        );
    }
    if let Some(p) = out {
        std::fs::write(&p, sdrs_cli::potential_bench::cases_json(&cases))?;
        println!("\ncases written to {p}");
    }
    Ok(())
}
