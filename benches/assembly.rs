//! `make bench` (assembly): one assembly of `block-plate-3d` H1 at the paper's 8×8 (our
//! 16×16 plan, 4 352 cells, 20.5k free unknowns), timed apart from everything else: residual
//! and tangent, and residual only, on a deformed and heated state. The figure behind
//! "assembly per Newton iteration per element" in Table 2, without the solver's noise.

mod common;
use common::{case_text, root};
use std::time::Instant;
use tmc::assembly::Assembler;
use tmc::case::Case;
use tmc::mesh::msh::read_msh;
use tmc::model::build;
use tmc::solve::mesh_for;

fn main() {
    let dir = root().join("target/bench/assembly");
    std::fs::create_dir_all(&dir).unwrap();
    let text = case_text("block-plate-3d-tm1").replace(
        "params = { nm = 1 }",
        "params = { n = 16, nb = 10, nm = 1, nq = 6 }",
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, &text).unwrap();
    let case = Case::parse(&path, text).unwrap();
    let mesh = read_msh(&mesh_for(&case, &dir).unwrap()).unwrap();
    let model = build(&case, mesh).unwrap();
    let cells: usize = model.mesh.cells.iter().map(|b| b.n_cells()).sum();
    let mut asm = Assembler::new(&model);
    // a smooth deformation and temperature field, so no law takes a shortcut at the identity
    let mut x = model.initial_state();
    for (d, v) in x.iter_mut().enumerate() {
        *v += 1e-3 * ((d % 17) as f64 / 17.0 - 0.5);
    }
    let repeats = 15;
    // twice the last-level cache, written between calls: what the factorisation between two
    // Newton iterations does to the cache
    let mut flush = vec![0u8; 64 << 20];
    let mut time = |tangent: bool, evict: bool| {
        let mut t: Vec<f64> = (0..repeats)
            .map(|i| {
                if evict {
                    flush.fill(i as u8);
                }
                let t0 = Instant::now();
                asm.assemble(&model, &x, 0.5, tangent, None).unwrap();
                t0.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        (t[0], t[repeats / 2])
    };
    let with_k = time(true, false);
    let evicted = time(true, true);
    let r_only = time(false, false);
    println!(
        "\nassembly of block-plate-3d H1 16×16 ({cells} cells, {} tangent entries), {} threads\n",
        asm.pattern.nnz(),
        rayon::current_num_threads()
    );
    println!("| assembly | best ms | median ms | median µs per cell |");
    println!("|---|---:|---:|---:|");
    for (label, (best, median)) in [
        ("residual + tangent", with_k),
        ("residual + tangent, cache evicted before", evicted),
        ("residual only", r_only),
    ] {
        println!(
            "| {label} | {:.1} | {:.1} | {:.2} |",
            best * 1e3,
            median * 1e3,
            median / cells as f64 * 1e6
        );
    }
    println!(
        "\npaper (12 cores): 2.3 s K & R / 203 iterations = 11.3 ms per iteration, 2.6 µs per cell"
    );
}
