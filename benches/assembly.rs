//! `make bench` (assembly): one assembly of `block-plate-3d` H1 with one medium layer, timed
//! apart from everything else, on a deformed and heated state: residual and tangent (with the
//! scatter's cache lines prefetched while the kernel runs, and without; after the cache was
//! evicted; after the threads idled 100 ms, as the second core does during a linear solve),
//! and residual only. The figure behind "assembly per Newton iteration per element" in
//! Table 2, without the solver's noise. The 16×16 plan (4 352 cells, 20.5k free unknowns)
//! always; the 32×32 plan (33 792 cells, 147k) with TMC_BENCH_LARGE=1.

mod common;
use common::{case_text, root};
use std::time::Instant;
use tmc::assembly::Assembler;
use tmc::case::Case;
use tmc::driver::mesh_for;
use tmc::model::build;

fn main() {
    // (plan, mesh parameters, the paper's K & R seconds and Newton iterations)
    let mut plans = vec![("16×16", "n = 16, nb = 10, nm = 1, nq = 6", 2.3, 203)];
    if std::env::var_os("TMC_BENCH_LARGE").is_some() {
        plans.push(("32×32", "n = 32, nb = 20, nm = 1, nq = 12", 15.4, 197));
    }
    for (plan, params, paper_s, paper_its) in plans {
        bench(plan, params, paper_s, paper_its);
    }
}

fn bench(plan: &str, params: &str, paper_s: f64, paper_its: usize) {
    let dir = root().join("target/bench/assembly").join(plan);
    std::fs::create_dir_all(&dir).unwrap();
    let text = case_text("block-plate-3d-tm1")
        .replace("params = { nm = 1 }", &format!("params = {{ {params} }}"));
    let path = dir.join("case.toml");
    std::fs::write(&path, &text).unwrap();
    let case = Case::parse(&path, text).unwrap();
    let (mesh, _staged) = mesh_for(&case, &dir).unwrap();
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
    // idle: the threads sleep 100 ms before each assembly, as during a linear solve that
    // leaves the second core idle
    let mut time = |tangent: bool, evict: bool, prefetch: bool, idle: bool| {
        asm.prefetch = prefetch;
        let mut t: Vec<f64> = (0..repeats)
            .map(|i| {
                if evict {
                    flush.fill(i as u8);
                }
                if idle {
                    std::thread::sleep(std::time::Duration::from_millis(100));
                }
                let t0 = Instant::now();
                asm.assemble(&model, &x, &model.path.step(0.0, 0.5), tangent, None)
                    .unwrap();
                t0.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        (t[0], t[repeats / 2])
    };
    let with_k = time(true, false, true, false);
    let evicted = time(true, true, true, false);
    let after_idle = time(true, false, true, true);
    let unfetched = time(true, false, false, false);
    let r_only = time(false, false, true, false);
    println!(
        "\nassembly of block-plate-3d H1 {plan} ({cells} cells, {} tangent entries), {} threads\n",
        asm.pattern.nnz(),
        rayon::current_num_threads()
    );
    println!("| assembly | best ms | median ms | median µs per cell |");
    println!("|---|---:|---:|---:|");
    for (label, (best, median)) in [
        ("residual + tangent", with_k),
        ("residual + tangent, cache evicted before", evicted),
        ("residual + tangent, threads idle 100 ms before", after_idle),
        ("residual + tangent, not prefetched", unfetched),
        ("residual only", r_only),
    ] {
        println!(
            "| {label} | {:.1} | {:.1} | {:.2} |",
            best * 1e3,
            median * 1e3,
            median / cells as f64 * 1e6
        );
    }
    let per_it = paper_s / paper_its as f64;
    println!(
        "\npaper (12 cores): {paper_s} s K & R / {paper_its} iterations = {:.1} ms per iteration, {:.2} µs per cell",
        per_it * 1e3,
        per_it / cells as f64 * 1e6
    );
}
