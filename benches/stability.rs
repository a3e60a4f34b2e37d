//! The stability suite's table: every hard case of `tests/it/common/hard.rs`, solved once, with
//! its load steps, Newton iterations, smallest J and result. `make bench` prints it; the
//! assertions are in `tests/it/stability.rs`.

#[path = "../tests/it/common/hard.rs"]
mod hard;

fn main() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-stability");
    println!(
        "\n{:<22} {:>6} {:>5} {:>6} {:>10} {:>10} {:>9} {:>7}  result / what",
        "case", "steps", "rej", "its", "min J sol", "min J med", "W/E - 1", "wall s"
    );
    for h in hard::all() {
        let t = std::time::Instant::now();
        let r = hard::solve(&h, &root.join(&h.name));
        let wall = t.elapsed().as_secs_f64();
        match r {
            Ok(s) => println!(
                "{:<22} {:>6} {:>5} {:>6} {:>10.2e} {:>10.2e} {:>9} {:>7.1}  λ = {} reached; {}",
                h.name,
                s.load_steps,
                s.rejected_steps,
                s.newton_iterations,
                s.min_J_solid.unwrap_or(f64::NAN),
                s.min_J_medium.unwrap_or(f64::NAN),
                if h.energy_tol.is_some() {
                    format!("{:+.1e}", s.external_work / s.energy - 1.0)
                } else {
                    "-".into()
                },
                wall,
                s.lambda,
                h.what
            ),
            Err(e) => println!("{:<22} failed: {e}", h.name),
        }
    }
}
