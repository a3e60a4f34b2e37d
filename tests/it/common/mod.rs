//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod hard;

use std::path::{Path, PathBuf};
use tmc::case::Case;
use tmc::driver::{SolveOptions, Summary, run};
use tmc::mesh::gmsh::{MeshOptions, mesh_geo};
use tmc::mesh::msh::read_msh;
use tmc::model::{Model, build};
use tmc::solver::idle::IdleThreads;

/// Every `.rs` file under `src/`, as paths relative to it.
pub fn source_files() -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path.strip_prefix(root).unwrap().to_owned());
            }
        }
    }
    let src = root().join("src");
    let mut files = Vec::new();
    walk(&src, &src, &mut files);
    files
}

/// `tmc args` in the project folder.
pub fn tmc(args: &[&str]) -> std::process::Output {
    tmc_with(args, &[])
}

/// `tmc args` with the environment variables `vars` set.
pub fn tmc_with(args: &[&str], vars: &[(&str, &str)]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args(args)
        .envs(vars.iter().copied())
        .current_dir(root())
        .output()
        .unwrap()
}

/// The arguments of `tmc solve CASE -q -o OUT`.
pub fn solve_args<'a>(case: &'a Path, out: &'a Path) -> Vec<&'a str> {
    vec![
        "solve",
        case.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]
}

/// `tmc solve CASE -q -o OUT` with `extra` arguments (e.g. `--set`).
pub fn solve_cli(case: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = solve_args(case, out);
    args.extend_from_slice(extra);
    tmc(&args)
}

/// `tmc solve case -q -o out`, sent Ctrl-C (SIGINT) as soon as its step 2 is written: the run
/// stops after the step it is in.
pub fn solve_interrupted(case: &Path, out: &Path) -> std::process::Output {
    solve_interrupted_after(case, out, 2)
}

/// [`solve_interrupted`] once its step `step` is written.
pub fn solve_interrupted_after(case: &Path, out: &Path, step: usize) -> std::process::Output {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args(solve_args(case, out))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !out.join(format!("step_{step:04}.vtu")).exists() {
        assert!(t0.elapsed().as_secs() < 300, "no step written");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    child.wait_with_output().unwrap()
}

/// `tmc mesh GEO -o OUT` (GEO relative to the project), which must succeed.
pub fn mesh_cli(geo: &str, out: &Path) {
    let o = tmc(&["mesh", geo, "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A results folder's `summary.json`.
pub fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch folder under target/, the calling test's own: under the test's name (the
/// name of the thread the test harness runs it on), so that two tests in this one binary
/// asking for the same `name` (the same shipped case, say) never share, nor delete each
/// other's, files.
pub fn scratch(name: &str) -> PathBuf {
    let thread = std::thread::current();
    let test = thread.name().filter(|t| *t != "main").unwrap_or("");
    let d = root()
        .join("target/test-scratch")
        .join(test.replace("::", "/"))
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The options of a quiet solve into `out`, in this process. Its pool's idle threads do what
/// `TMC_IDLE_THREADS` says, as `tmc solve` reads it: `make test` sets it to `sleep`, as it
/// runs more tests at once than there are CPUs, where a thread spinning for its solve's next
/// parallel work would take the CPU another test's solve is waiting for.
pub fn quiet(out: Option<PathBuf>) -> SolveOptions {
    let idle_threads = match std::env::var(IdleThreads::VAR) {
        Ok(v) => IdleThreads::parse(&v).unwrap_or_else(|e| panic!("{e}")),
        Err(_) => IdleThreads::default(),
    };
    SolveOptions {
        out_dir: out,
        quiet: true,
        idle_threads,
        ..Default::default()
    }
}

/// Solve `cases/NAME.toml` into a scratch folder, a `.vtu` of its first and its last state
/// only (as [`ENDS_ONLY`]: none of the tests reads the steps between).
pub fn solve_case(name: &str) -> (Summary, PathBuf) {
    let out = scratch(name);
    let opts = SolveOptions {
        sets: vec![("output.every".into(), "1000000".into())],
        ..quiet(Some(out.clone()))
    };
    let s = run(&root().join("cases").join(format!("{name}.toml")), &opts)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    (s, out)
}

/// Read a history.csv into (columns, rows).
pub fn history(dir: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let h = tmc::plot::History::read(&dir.join("history.csv")).unwrap();
    (h.columns, h.rows)
}

/// The histories of a run (`full`) and of the same run stopped and continued (`out`): the same
/// columns and rows, every value but the wall time to the last bit.
pub fn same_history_to_the_bit(full: &Path, out: &Path) {
    same_columns_to_the_bit(full, out, &["wall_seconds"]);
}

/// As [`same_history_to_the_bit`], the Krylov counts aside: a run continued where the engine
/// refines with GMRES factors afresh at its first step, where the uninterrupted run
/// preconditioned with the factor it kept from the step before (measured: one iteration
/// fewer in that step, the state to the last bit).
pub fn same_state_to_the_bit(full: &Path, out: &Path) {
    same_columns_to_the_bit(full, out, &["wall_seconds", "krylov_iterations"]);
}

fn same_columns_to_the_bit(full: &Path, out: &Path, aside: &[&str]) {
    let ((cols, expected), (cols2, rows)) = (history(full), history(out));
    assert_eq!(cols, cols2);
    assert_eq!(rows.len(), expected.len(), "rows");
    for (i, (a, b)) in expected.iter().zip(&rows).enumerate() {
        for (j, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                aside.contains(&cols[j].as_str())
                    || x.to_bits() == y.to_bits()
                    || (x.is_nan() && y.is_nan()),
                "row {i}, {}: {x} vs {y}",
                cols[j]
            );
        }
    }
}

/// Solve a case given as text (its `mesh` key is prepended: `geo/GEO`, meshed with `params`)
/// in a scratch folder.
pub fn solve_text(tag: &str, geo: &str, params: &str, case_text: &str) -> (Summary, PathBuf) {
    solve_text_opts(tag, geo, &format!("params = {{ {params} }}"), case_text)
}

/// An `[output]` table for a case whose test reads its history, its summary and its last
/// state only: a `.vtu` of the first and the last state (on a mesh of a few hundred nodes,
/// a `.vtu` per step is 40 % of a run's time).
pub const ENDS_ONLY: &str = "\n[output]\nevery = 1000000\n";

/// `case.toml` in the scratch folder `tag`: `case_text` on `geo/GEO` meshed with the whole
/// `[mesh_options]` body `options`. Its results go to `out` beside it.
pub fn case_file(tag: &str, geo: &str, options: &str, case_text: &str) -> PathBuf {
    let text = format!(
        "mesh = \"{}\"\n[mesh_options]\n{options}\n{case_text}",
        root().join("geo").join(geo).display()
    );
    let path = scratch(tag).join("case.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// As [`solve_text`], with the whole `[mesh_options]` body (e.g. `order = 2`).
pub fn solve_text_opts(tag: &str, geo: &str, options: &str, case_text: &str) -> (Summary, PathBuf) {
    let path = case_file(tag, geo, options, case_text);
    let out = path.with_file_name("out");
    let s = run(&path, &quiet(Some(out.clone()))).unwrap_or_else(|e| panic!("{tag}: {e}"));
    (s, out)
}

/// `cases/NAME.toml` with its mesh path made absolute, so that it can be written anywhere.
pub fn shipped_case(name: &str) -> String {
    std::fs::read_to_string(root().join(format!("cases/{name}.toml")))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()))
}

/// The body of a case file without its `mesh` key and header comments.
pub fn case_body(name: &str) -> String {
    hard::body_of(name)
}

/// Build a model from case text (paths relative to cases/) and a .geo meshed into scratch.
pub fn model_from(case_text: &str, geo: &str, tag: &str) -> (Case, Model) {
    model_with(case_text, geo, &[], tag)
}

/// As [`model_from`], with `.geo` parameters.
pub fn model_with(case_text: &str, geo: &str, params: &[(&str, f64)], tag: &str) -> (Case, Model) {
    model_order(case_text, geo, params, (1, false), tag)
}

/// As [`model_with`], meshed with element `order` (1 or 2) and `incomplete` (serendipity).
pub fn model_order(
    case_text: &str,
    geo: &str,
    params: &[(&str, f64)],
    (order, incomplete): (u8, bool),
    tag: &str,
) -> (Case, Model) {
    let dir = scratch(tag);
    let msh = dir.join("mesh.msh");
    mesh_geo(
        &root().join("geo").join(geo),
        &msh,
        &MeshOptions {
            order,
            incomplete,
            set_numbers: params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            ..Default::default()
        },
    )
    .unwrap();
    let text = format!("mesh = \"{}\"\n{case_text}", msh.display());
    let case = Case::parse(&dir.join("case.toml"), text).unwrap();
    let mesh = read_msh(&msh).unwrap();
    tmc::model::validate::validate(&case, &mesh).unwrap();
    let model = build(&case, mesh).unwrap();
    (case, model)
}

/// A cell-data array of a written .vtu, flattened.
pub fn cell_array(vtu: &Path, name: &str) -> Vec<f64> {
    vtu_array(vtu, name, false)
}

/// The largest difference between two arrays of the same length, and the largest size of
/// the first: (max |a − b|, max |a|), what a comparison to a relative tolerance needs.
pub fn largest_difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "arrays of different lengths");
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    (worst, scale)
}

/// A point-data array of a written .vtu, flattened.
pub fn point_array(vtu: &Path, name: &str) -> Vec<f64> {
    vtu_array(vtu, name, true)
}

fn vtu_array(vtu: &Path, name: &str, point: bool) -> Vec<f64> {
    use vtkio::model::{Attribute, DataSet, Piece};
    let vtk = vtkio::Vtk::import(vtu).unwrap_or_else(|e| panic!("{}: {e}", vtu.display()));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not a grid")
    };
    let Piece::Inline(p) = &pieces[0] else {
        panic!("not inline")
    };
    for a in if point { &p.data.point } else { &p.data.cell } {
        if let Attribute::DataArray(d) = a
            && d.name == name
        {
            return d.data.clone().cast_into::<f64>().unwrap();
        }
    }
    panic!("no array {name} in {}", vtu.display())
}

/// `mpirun -n RANKS tmc`, as root and on more ranks than cores if need be, to add arguments to.
/// Each job has a session directory of its own: Open MPI 4.1's jobs started at the same moment
/// race to make their shared one, and the loser ends in orte_init ("A call to mkdir was unable
/// to create the desired directory ... File exists"; seen once in a whole run of the tests).
#[allow(dead_code)]
pub fn mpirun_command(ranks: usize) -> std::process::Command {
    let mut c = std::process::Command::new("mpirun");
    c.args(["-n", &ranks.to_string(), env!("CARGO_BIN_EXE_tmc")])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .env("OMPI_MCA_orte_tmpdir_base", mpi_session())
        .current_dir(root());
    c
}

/// A new folder for one `mpirun` job's session, under a folder of this test process's (Open
/// MPI empties it as the job ends). The folders of test processes that have ended are removed
/// the first time.
fn mpi_session() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    static SWEPT: std::sync::Once = std::sync::Once::new();
    let tmp = std::env::temp_dir();
    SWEPT.call_once(|| {
        for e in std::fs::read_dir(&tmp).into_iter().flatten().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let pid = name
                .strip_prefix("tmc-it-ompi-")
                .and_then(|p| p.parse::<u32>().ok());
            if pid.is_some_and(|p| !Path::new(&format!("/proc/{p}")).exists()) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    });
    let k = NEXT.fetch_add(1, Ordering::Relaxed);
    let dir = tmp.join(format!("tmc-it-ompi-{}/{k}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `mpirun -n RANKS` of tmc with `args`.
#[allow(dead_code)]
pub fn mpirun_tmc(ranks: usize, args: &[&std::ffi::OsStr]) -> std::process::Output {
    mpirun_command(ranks).args(args).output().unwrap()
}
