//! `make bench` (output): one step's `.vtu` of `block-plate-3d` H1 with one medium layer
//! (16×16 plan: 4 352 cells, 27k nodes) on a deformed and heated state, written uncompressed
//! and at zlib levels 1 (tmc's choice) and 6 (zlib's default): file size and write time,
//! best of 5, post-processing (cell and nodal fields) included.

mod common;
use common::{case_text, root};
use std::time::Instant;
use tmc::case::Case;
use tmc::driver::mesh_for;
use tmc::model::build;
use tmc::output::Series;
use tmc::output::contact::ContactFaces;

fn main() {
    let dir = root().join("target/bench/output");
    std::fs::create_dir_all(&dir).unwrap();
    let text = case_text("block-plate-3d-tm1").replace(
        "params = { nm = 1 }",
        "params = { n = 16, nb = 10, nm = 1, nq = 6 }",
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, &text).unwrap();
    let case = Case::parse(&path, text).unwrap();
    let (mesh, _staged) = mesh_for(&case, &dir).unwrap();
    let model = build(&case, mesh).unwrap();
    let mut x = model.initial_state();
    for (d, v) in x.iter_mut().enumerate() {
        *v += 1e-3 * ((d % 17) as f64 / 17.0 - 0.5);
    }
    println!(
        "one step's .vtu, block-plate-3d H1 16×16 ({} nodes, {} cells)",
        model.mesh.coords.len(),
        model.mesh.n_cells()
    );
    println!("| encoding | size (MB) | write (ms, best of 5) |");
    println!("|---|---:|---:|");
    let mut series = Series::new(&dir, "bench", &model, ContactFaces::of(&model));
    let references = tmc::assembly::References::new(&model);
    for (name, level) in [("uncompressed", 0), ("zlib 1 (tmc)", 1), ("zlib 6", 6)] {
        series.zlib_level = level;
        let mut best = f64::INFINITY;
        for step in 0..5 {
            let t = Instant::now();
            series
                .write(&model, step, &references, &x, step as f64, None)
                .unwrap();
            best = best.min(t.elapsed().as_secs_f64());
        }
        let size = std::fs::metadata(dir.join(series.file_name(4)))
            .unwrap()
            .len();
        println!("| {name} | {:.2} | {:.0} |", size as f64 / 1e6, best * 1e3);
    }
}
