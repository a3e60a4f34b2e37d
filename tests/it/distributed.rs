//! The PETSc engine (`--features petsc`): on one process (`[solver] engine = "petsc"`) and on
//! two ranks (`mpirun -n 2`) a run gives the serial faer run's answers: the same steps and
//! Newton iterations, every nodal value to 1e-8 of its field's largest, and it stops with
//! clear errors on what it cannot run.
#![cfg(feature = "petsc")]

use crate::common;

use common::{case_body, case_file, point_array, root, scratch, solve_cli, stderr, summary, tmc};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `mpirun -n ranks tmc solve CASE -q -o OUT extra…` (as root too: CI runs as root).
fn mpirun(ranks: usize, case: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    common::mpirun_tmc(ranks, &solve_args(case, out, extra))
}

/// [`mpirun`] of several jobs started together, their outputs in order. For refusals: Open MPI
/// waits a second or two after a rank ends with an error before it ends the job, time the
/// jobs can spend side by side.
fn mpirun_together(jobs: &[(usize, Vec<&std::ffi::OsStr>)]) -> Vec<std::process::Output> {
    let started: Vec<std::process::Child> = (jobs.iter())
        .map(|(ranks, args)| {
            common::mpirun_command(*ranks)
                .args(args)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    started
        .into_iter()
        .map(|job| job.wait_with_output().unwrap())
        .collect()
}

fn solve_args<'a>(case: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a std::ffi::OsStr> {
    let mut args = vec![
        "solve".as_ref(),
        case.as_os_str(),
        "-q".as_ref(),
        "-o".as_ref(),
    ];
    args.push(out.as_os_str());
    args.extend(extra.iter().map(|e| std::ffi::OsStr::new(*e)));
    args
}

/// The last step file of a run: its `.vtu`, or on several ranks the `.pvtu` of its parts.
fn last_step(dir: &Path) -> PathBuf {
    let mut steps: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            name.ends_with(".pvtu") || (name.ends_with(".vtu") && name.matches('_').count() == 1)
        })
        .collect();
    steps.sort();
    steps.pop().expect("a step file")
}

/// A point array of a step: read from its `.vtu`, or put together from the parts its `.pvtu`
/// names (each point carries its mesh node number), read by vtkio.
fn step_points(step: &Path, name: &str) -> Vec<f64> {
    use vtkio::model::{Attribute, DataSet, Piece};
    if step.extension().is_some_and(|e| e == "vtu") {
        return point_array(step, name);
    }
    let mut vtk = vtkio::Vtk::import(step).unwrap_or_else(|e| panic!("{}: {e}", step.display()));
    vtk.load_all_pieces().unwrap();
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not a grid")
    };
    assert!(pieces.len() > 1, "{}: one part", step.display());
    let mut whole: Vec<Option<f64>> = Vec::new();
    for piece in &pieces {
        let Piece::Inline(p) = piece else {
            panic!("part not loaded")
        };
        let array = |n: &str| -> (Vec<f64>, usize) {
            p.data
                .point
                .iter()
                .find_map(|a| match a {
                    Attribute::DataArray(d) if d.name == n => Some((
                        d.data.clone().cast_into::<f64>().unwrap(),
                        d.elem.num_comp() as usize,
                    )),
                    _ => None,
                })
                .unwrap_or_else(|| panic!("no {n} in a part of {}", step.display()))
        };
        let (nodes, _) = array("node");
        let (values, k) = array(name);
        for (i, &n) in nodes.iter().enumerate() {
            let n = n as usize;
            if whole.len() < (n + 1) * k {
                whole.resize((n + 1) * k, None);
            }
            for c in 0..k {
                let v = values[i * k + c];
                // a node on a cut is in both parts, with the same value
                assert!(
                    whole[n * k + c].is_none_or(|w| w == v),
                    "{name} at node {n}"
                );
                whole[n * k + c] = Some(v);
            }
        }
    }
    whole
        .into_iter()
        .map(|v| v.expect("every node in some part"))
        .collect()
}

/// The point array `field` of the serial run's step file `serial` and of the step `step` of
/// a run on PETSc (one `.vtu`, or a `.pvtu` and its parts) agree to 1e-8 of its largest value.
fn same_field(serial: &Path, step: &Path, field: &str, label: &str) {
    let (x, y) = (point_array(serial, field), step_points(step, field));
    assert_eq!(x.len(), y.len(), "{label}: {field}");
    let (worst, scale) = common::largest_difference(&x, &y);
    assert!(
        worst <= 1e-8 * scale.max(f64::MIN_POSITIVE),
        "{label}: {field} differs by {worst:.2e} (largest {scale:.2e})"
    );
}

/// Run `name` three ways (faer, PETSc on one process, PETSc on two ranks) and compare the
/// last states and the counts; the PETSc runs' summaries.
fn same_answers(name: &str, extra: &[&str]) -> [serde_json::Value; 2] {
    let case = root().join("cases").join(format!("{name}.toml"));
    let settings: String = (extra.concat().chars())
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let tag = format!("distributed-{name}-{settings}");
    let dirs = [1, 2, 3].map(|i| scratch(&format!("{tag}-{i}")));
    let ok = |o: std::process::Output, how: &str| {
        assert!(o.status.success(), "{name} {how}: {}", stderr(&o));
    };
    ok(solve_cli(&case, &dirs[0], extra), "faer");
    let mut petsc = extra.to_vec();
    petsc.extend(["--set", "solver.engine=\"petsc\""]);
    ok(solve_cli(&case, &dirs[1], &petsc), "petsc");
    ok(mpirun(2, &case, &dirs[2], extra), "mpirun -n 2");
    let serial = summary(&dirs[0]);
    for (dir, ranks) in [(&dirs[1], 1), (&dirs[2], 2)] {
        let s = summary(dir);
        assert_eq!(s["engine"], "petsc");
        assert_eq!(s["ranks"], ranks);
        assert_eq!(s["converged"], true, "{name} on {ranks} ranks");
        for key in ["load_steps", "rejected_steps", "newton_iterations"] {
            assert_eq!(s[key], serial[key], "{name} on {ranks} ranks: {key}");
        }
        let (a, b) = (last_step(&dirs[0]), last_step(dir));
        assert_eq!(a.file_stem(), b.file_stem());
        assert_eq!(
            b.extension().unwrap(),
            if ranks == 1 { "vtu" } else { "pvtu" }
        );
        if ranks == 2 {
            // the collection lists the .pvtu files; the manifest, every part, so that the
            // next run in this folder replaces them
            let stem = b.file_stem().unwrap().to_string_lossy().into_owned();
            let pvd = std::fs::read_to_string(dir.join(format!("{name}.pvd"))).unwrap();
            assert!(pvd.contains(&format!("file=\"{stem}.pvtu\"")), "{pvd}");
            assert!(!pvd.contains(".vtu\""), "{pvd}");
            let manifest = std::fs::read_to_string(dir.join(".tmc-manifest")).unwrap();
            for part in [0, 1] {
                let file = format!("{stem}_{part}.vtu");
                assert!(
                    manifest.lines().any(|l| l == file),
                    "{file} not in the manifest"
                );
                assert!(dir.join(&file).exists());
            }
        }
        for field in ["u", "theta", "p"]
            .into_iter()
            .filter(|f| serial["dofs"][f] != 0)
        {
            same_field(&a, &b, field, &format!("{name} on {ranks} ranks"));
        }
        // the contact on the solids' faces, each rank's part from the forces of every rank's
        // medium cells
        for field in ["contact_pressure", "contact_shear"] {
            same_field(&a, &b, field, &format!("{name} on {ranks} ranks"));
        }
    }
    if let Some(each) = summary(&dirs[2])["peak_memory_mb_ranks"].as_array() {
        assert_eq!(each.len(), 2);
    } else {
        panic!("{name}: no memory per rank");
    }
    [summary(&dirs[1]), summary(&dirs[2])]
}

#[test]
fn the_block_is_the_same_on_petsc_and_on_two_ranks() {
    same_answers("block", &[]);
}

#[test]
fn multigrid_gives_the_direct_answers_on_the_closing_block() {
    // one-way: GMRES around a field split of the mechanics (GAMG with the rigid motions as
    // near-kernel on the solid, MUMPS on the medium's rows), then heat the same way
    // (BoomerAMG on the solid); the medium closes to a gap of 2.94e-4
    for s in same_answers("block", &["--set", "solver.petsc.method=\"multigrid\""]) {
        assert_eq!(s["petsc_solver"], "gmres/fieldsplit");
        let per_update =
            s["krylov_iterations"].as_f64().unwrap() / s["linear_solves"].as_f64().unwrap();
        assert!(
            per_update >= 1.0,
            "{per_update} Krylov iterations per update"
        );
        let gap = s["probes"]["gap"].as_f64().unwrap();
        assert!((gap - 2.9420e-4).abs() < 1e-8, "gap {gap}");
    }
}

#[test]
fn auto_takes_petsc_s_multigrid_where_faer_s_factors_do_not_fit() {
    // the block's faer factors take a few MB: with a budget of 1 MB, `engine = "auto"` (the
    // default) solves on PETSc's multigrid, says why, and gets the direct solvers' gap; with
    // the machine's memory, or with `engine = "faer"` asked for, faer
    let case = root().join("cases/block.toml");
    let report = |extra: &[&str]| {
        let mut args = vec!["check", case.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = tmc(&args);
        let r = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
        assert!(o.status.success(), "{r}");
        r
    };
    let r = report(&["--memory", "1"]);
    assert!(
        r.contains("engine \"auto\": PETSc's multigrid, since a run on faer would take about")
            && r.contains("more than the 1 MB it has")
            && r.contains("linear solver: mechanics: petsc"),
        "{r}"
    );
    for faer in [
        report(&[]),
        report(&["--memory", "1", "--set", "solver.engine=\"faer\""]),
    ] {
        assert!(
            faer.contains("linear solver: mechanics: faer") && !faer.contains("engine \"auto\""),
            "{faer}"
        );
    }
    // faer asked for, or a linear solver: it runs as asked, and says it does not fit
    let asked = report(&["--memory", "1", "--set", "solver.engine=\"faer\""]);
    assert!(
        asked.contains("warning: engine \"faer\": a run on faer would take about")
            && asked.contains("more than the 1 MB it has"),
        "{asked}"
    );
    let lu = report(&["--memory", "1", "--set", "solver.linear=\"lu\""]);
    assert!(
        lu.contains("warning: a `linear` solver given: a run on faer would take about"),
        "{lu}"
    );
    assert!(
        !report(&[]).contains("warning:"),
        "the machine's memory is enough"
    );
    // [solver.petsc] beside engine = "faer" on one process: said to be ignored
    let ignored = report(&[
        "--set",
        "solver.engine=\"faer\"",
        "--set",
        "solver.petsc.method=\"multigrid\"",
    ]);
    assert!(
        ignored.contains(
            "warning: engine \"faer\": [solver.petsc] is for the PETSc engine, and this run on \
             one process ignores it"
        ),
        "{ignored}"
    );
    let out = scratch("auto-memory");
    let o = common::tmc_with(
        &[
            "solve",
            case.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ],
        &[("TMC_MEMORY_MB", "1")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["engine"], "petsc");
    assert_eq!(s["petsc_solver"], "gmres/fieldsplit");
    let gap = s["probes"]["gap"].as_f64().unwrap();
    assert!((gap - 2.9420e-4).abs() < 1e-8, "gap {gap}");
}

#[test]
fn multigrid_survives_the_closing_medium_in_3d() {
    // monolithic, the whole load path: the medium closes to J = 2e-4 under the plate, where a
    // multigrid over the whole system broke down (GMRES breakdown at λ ≈ 0.46 with GAMG on
    // u + p); with the medium's rows solved directly the Krylov iterations stay bounded and
    // every step and Newton iteration is the direct solvers'. On 4 x 4 cells in plan and 3
    // and 2 cells through block and plate rather than the case's 8 x 8, 5 and 3 (1.0k
    // unknowns): the medium closes nearly as far (J = 2.8e-4 against 2.0e-4; 2.7e-4 on 6 x 6,
    // at three times the time, with as many Krylov iterations per update)
    let s = same_answers(
        "block-plate-3d",
        &[
            "--set",
            "solver.petsc.method=\"multigrid\"",
            "--set",
            "mesh_options.params={n=4,nb=3,nq=2}",
        ],
    );
    for s in s {
        assert_eq!(s["petsc_solver"], "gmres/fieldsplit");
        assert_eq!(s["lambda"], 1.0);
        let per_update =
            s["krylov_iterations"].as_f64().unwrap() / s["linear_solves"].as_f64().unwrap();
        // measured: 57 per update on 1 rank (56 on 6 x 6; 70 and 69 on 1 and 2 ranks at 4.5k
        // unknowns)
        assert!(
            (10.0..100.0).contains(&per_update),
            "{per_update} Krylov iterations per update"
        );
    }
}

#[test]
fn quadratic_cells_are_the_same_on_petsc_and_on_two_ranks() {
    same_answers(
        "block",
        &[
            "--set",
            "mesh_options.order=2",
            "--set",
            "mesh_options.params={n=8,m=8,l=2}",
        ],
    );
}

#[test]
fn the_one_way_two_blocks_are_the_same_on_petsc_and_on_two_ranks() {
    same_answers("two-blocks", &[]);
}

#[test]
fn the_3d_monolithic_block_plate_is_the_same_on_petsc_and_on_two_ranks() {
    // the load path to λ = 0.4 (5 of its 14 steps): the coupled u, θ and p on PETSc's direct
    // solver and on two ranks; the whole path, where the medium closes, is run by
    // `multigrid_survives_the_closing_medium_in_3d` (its multigrid is the harder solve)
    let s = same_answers("block-plate-3d", &["--set", "steps.path=[0, 0.4]"]);
    for s in s {
        assert_eq!(s["lambda"], 0.4);
        assert!(
            s["load_steps"].as_u64().unwrap() >= 4,
            "{}",
            s["load_steps"]
        );
    }
}

/// The block on PETSc (one process) with `--set KEY=VALUE` into `tag`: the run's output.
fn block_on_petsc(tag: &str, key_value: &str) -> (std::process::Output, PathBuf) {
    scene_on_petsc("block", tag, key_value)
}

/// `cases/SCENE.toml` on PETSc (one process) with `--set KEY=VALUE` into `tag`.
fn scene_on_petsc(scene: &str, tag: &str, key_value: &str) -> (std::process::Output, PathBuf) {
    let case = root().join(format!("cases/{scene}.toml"));
    let out = scratch(tag);
    let petsc = ["--set", "solver.engine=\"petsc\"", "--set", key_value];
    (solve_cli(&case, &out, &petsc), out)
}

#[test]
fn a_misspelt_petsc_option_is_an_error() {
    // the block holds a temperature in full from λ = 0 (its first solve settles step 0); the
    // slab ramps everything (its first solve is step 1's): an engine's failure is no reason
    // to cut a step, and ends the run either way, before its first step: a set-up failure,
    // which leaves no results
    for scene in ["block", "slab-conduction"] {
        let (o, out) = scene_on_petsc(
            scene,
            &format!("distributed-bad-option-{scene}"),
            "solver.petsc.options=\"-ksp_typo cg\"",
        );
        assert!(!o.status.success(), "{scene}");
        let e = stderr(&o);
        assert!(
            e.contains("-ksp_typo cg") && e.contains("did not use") && !e.contains("ramp"),
            "{scene}: {e}"
        );
        assert!(!e.contains("below the minimum"), "{scene}: {e}");
        assert_eq!(folder_files(&out), BTreeMap::new(), "{scene}");
    }
}

/// Every file in `dir` (and its hidden ones) with its bytes.
fn folder_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let bytes = std::fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect()
}

/// The folder's files `now` are those `before`, byte for byte (the names of any that differ
/// said, with `err`).
fn same_files(now: &BTreeMap<String, Vec<u8>>, before: &BTreeMap<String, Vec<u8>>, err: &str) {
    let names = |m: &BTreeMap<String, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(now), names(before), "{err}");
    let changed: Vec<&String> = (now.iter())
        .filter(|(name, bytes)| before[*name] != **bytes)
        .map(|(name, _)| name)
        .collect();
    assert!(changed.is_empty(), "changed: {changed:?}; {err}");
}

#[test]
fn a_rerun_failing_on_its_engine_or_on_one_rank_leaves_the_previous_results_as_they_were() {
    // before, the previous run's files were removed once the case and model were checked, and
    // the engine failed after: on an option PETSc refused (set-up), or one it did not use
    // (known at the first solve), on one process and on two ranks
    let case = root().join("cases/block.toml");
    let out = scratch("distributed-rerun-kept");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = folder_files(&out);
    assert!(before.contains_key("history.csv") && before.contains_key("summary.json"));
    for (ranks, options, says) in [
        (
            1,
            "-ksp_type nonsense",
            "Unable to find requested KSP type nonsense",
        ),
        (1, "-ksp_typo cg", "did not use the option(s) -ksp_typo cg"),
        (
            2,
            "-ksp_type nonsense",
            "Unable to find requested KSP type nonsense",
        ),
        (2, "-ksp_typo cg", "did not use the option(s) -ksp_typo cg"),
    ] {
        let set = format!("solver.petsc.options=\"{options}\"");
        let args = ["--set", "solver.engine=\"petsc\"", "--set", &set];
        let o = match ranks {
            1 => solve_cli(&case, &out, &args),
            _ => mpirun(ranks, &case, &out, &args),
        };
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{ranks} {options}: {e}");
        assert_eq!(e.matches(says).count(), 1, "{ranks} {options}: {e}");
        assert!(
            folder_files(&out) == before,
            "{ranks} ranks, {options}: the folder changed"
        );
    }
    // a rank that fails alone: the second cannot write its part of step 1, a folder of the
    // user's in the way; both end on it, and the previous run comes back (before, putting it
    // back stopped at that folder and left it aside)
    std::fs::create_dir(out.join("step_0001_1.vtu")).unwrap();
    let before = folder_files(&out);
    let o = mpirun(2, &case, &out, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(
        e.matches("step_0001_1.vtu: Is a directory").count(),
        1,
        "{e}"
    );
    assert!(folder_files(&out) == before, "the folder changed: {e}");
}

#[test]
fn petsc_failures_are_told_in_petsc_s_words() {
    // (options, what stderr must say): a solver stopped by its iteration limit names its
    // KSPConvergedReason; a failed call names the call, PETSc's text and where it was raised
    let cases = [
        (
            "-ksp_type gmres -pc_type jacobi -ksp_max_it 1",
            vec!["gmres/jacobi did not converge (DIVERGED_ITS, KSPConvergedReason -3)"],
        ),
        (
            "-ksp_type gmres -pc_type jacobi -ksp_max_it 1 -ksp_error_if_not_converged",
            vec!["KSPSolve failed", "reason DIVERGED_ITS", "(error 91)"],
        ),
        (
            "-ksp_type nonsense",
            vec![
                "KSPSetFromOptions failed",
                "Unable to find requested KSP type nonsense",
                "(in KSPSetType)",
            ],
        ),
    ];
    for (i, (options, says)) in cases.iter().enumerate() {
        let (o, _) = block_on_petsc(
            &format!("distributed-petsc-words-{i}"),
            &format!("solver.petsc.options=\"{options}\""),
        );
        assert!(!o.status.success(), "{options}");
        let e = stderr(&o);
        for s in says {
            assert!(e.contains(s), "{options}: {s} not in {e}");
        }
        // one statement of it, no advice about ramps, no "unknown error"
        assert_eq!(e.matches("error:").count(), 1, "{options}: {e}");
        assert!(!e.contains("caused by") && !e.contains("ramp") && !e.contains("unknown"));
    }
}

#[test]
fn log_view_in_the_case_s_options_prints_petsc_s_log() {
    // PETSc reads -log_view when it starts, before the case's options are in: it was left
    // unused and refused as misspelt
    let (o, out) = block_on_petsc("distributed-log-view", "solver.petsc.options=\"-log_view\"");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("PETSc Performance Summary"));
    assert_eq!(summary(&out)["converged"], true);
}

#[test]
fn faer_s_linear_choice_on_petsc_is_an_error() {
    let (o, _) = block_on_petsc("distributed-bad-linear", "solver.linear=\"lu\"");
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("[solver.petsc] options"), "{e}");
}

/// GMRES with algebraic multigrid (GAMG) as the options ask: the same gap as the direct
/// solvers, with Krylov iterations counted. (CG with GAMG stops on this scene's closing medium:
/// its preconditioner turns indefinite, PETSc's reason −8.)
#[test]
fn petsc_options_choose_the_solver() {
    let (o, out) = block_on_petsc(
        "distributed-gmres-gamg",
        "solver.petsc.options=\"-ksp_type gmres -pc_type gamg -ksp_rtol 1e-12\"",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["petsc_solver"], "gmres/gamg");
    assert!(s["krylov_iterations"].as_u64().unwrap() > 0);
    // the block's gap as the direct solvers give it (tests/it/medium.rs): 2.942e-4
    let gap = s["probes"]["gap"].as_f64().unwrap();
    assert!((gap - 2.9420e-4).abs() < 1e-7, "gap {gap}");
}

/// A direct solver chosen by options under `method = "multigrid"` factorises every matrix:
/// the multigrid's habit of keeping its preconditioner across Newton updates would make
/// "preonly" solve with an old matrix (a modified Newton: more iterations, another path).
#[test]
fn a_direct_solver_under_the_multigrid_method_keeps_no_old_factor() {
    let case = root().join("cases/block.toml");
    let run = |tag: &str, extra: &[&str]| {
        let out = scratch(tag);
        let mut args = vec!["--set", "solver.engine=\"petsc\""];
        args.extend_from_slice(extra);
        let o = solve_cli(&case, &out, &args);
        assert!(o.status.success(), "{tag}: {}", stderr(&o));
        summary(&out)
    };
    let direct = run("distributed-direct", &[]);
    let preonly = run(
        "distributed-multigrid-preonly",
        &[
            "--set",
            "solver.petsc.method=\"multigrid\"",
            "--set",
            "solver.petsc.options=\"-ksp_type preonly -pc_type lu -pc_factor_mat_solver_type mumps\"",
        ],
    );
    assert_eq!(preonly["petsc_solver"], "preonly/lu");
    for key in ["load_steps", "newton_iterations", "linear_solves"] {
        assert_eq!(preonly[key], direct[key], "{key}");
    }
    let gap = |s: &serde_json::Value| s["probes"]["gap"].as_f64().unwrap();
    assert!((gap(&preonly) - gap(&direct)).abs() < 1e-9 * gap(&direct));
}

#[test]
fn verbose_under_mpirun_prints_each_step_once() {
    // before, --verbose made every rank print the step lines and the Newton tables
    let case = root().join("cases/block.toml");
    let out = scratch("distributed-verbose");
    let args = ["solve".as_ref(), case.as_os_str(), "--verbose".as_ref()];
    let o = common::mpirun_tmc(2, &[&args[..], &["-o".as_ref(), out.as_os_str()]].concat());
    let (said, e) = (String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert!(o.status.success(), "{e}");
    let all = format!("{said}{e}");
    let steps = summary(&out)["load_steps"].as_u64().unwrap();
    for step in 1..=steps {
        let line = format!("step {step:3}  ");
        assert_eq!(all.matches(&line).count(), 1, "{line:?} in {all}");
    }
}

#[test]
fn a_bad_input_under_mpirun_ends_every_rank_with_the_error_printed_once() {
    // before, rank 0 told the others of its failure with an empty broadcast, which Open MPI
    // refused (MPI_ERR_ARG): the job aborted with exit 13 and the message was lost
    let good = std::fs::read_to_string(root().join("cases/friction-heating.toml"))
        .unwrap()
        .replace("../geo/", &format!("{}/geo/", root().display()));
    let dir = scratch("distributed-bad-inputs");
    std::fs::create_dir_all(&dir).unwrap();
    let a_file = dir.join("a-file");
    std::fs::write(&a_file, "the user's").unwrap();
    let cases = [
        (
            "normal.toml",
            good.replace("normal = [0, 1]", "normal = [0, 1, 0]"),
            "`friction.normal` has 3 components",
        ),
        (
            "group.toml",
            good.replacen("group = \"bottom\"", "group = \"nothere\"", 1),
            "\"nothere\" is not in the mesh",
        ),
    ];
    let files: Vec<(PathBuf, PathBuf)> = (cases.iter())
        .map(|(name, text, _)| {
            let case = dir.join(name);
            std::fs::write(&case, text).unwrap();
            (case, dir.join(format!("out-{name}")))
        })
        .collect();
    // and -o naming a file: refused, the file kept
    let case = dir.join("good.toml");
    std::fs::write(&case, &good).unwrap();
    // and a study, which starts its variants as processes of their own, which cannot start
    // MPI inside the job: refused at once (before, the variants failed in MPI_Init or the
    // ranks hung)
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        format!(
            "case = \"{}\"\n[[variant]]\nname = \"a\"\nset = {{ \"time.dt\" = 0.05 }}\n",
            case.display()
        ),
    )
    .unwrap();
    let study_out = dir.join("study-out");
    let mut jobs: Vec<_> = (files.iter())
        .map(|(case, out)| (2, solve_args(case, out, &[])))
        .collect();
    jobs.push((2, solve_args(&case, &a_file, &[])));
    let study_args = ["study".as_ref(), study.as_os_str(), "-o".as_ref()];
    jobs.push((2, [&study_args[..], &[study_out.as_os_str()]].concat()));
    let mut ended = mpirun_together(&jobs);
    let (studied, o) = (ended.pop().unwrap(), ended.pop().unwrap());
    for ((name, _, says), o) in cases.iter().zip(ended) {
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {e}");
        assert_eq!(e.matches(says).count(), 1, "{name}: {e}");
        assert!(!e.contains("MPI_ERR"), "{name}: {e}");
    }
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!stderr(&o).contains("MPI_ERR"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&a_file).unwrap(), "the user's");
    let e = stderr(&studied);
    assert_eq!(studied.status.code(), Some(1), "{e}");
    assert_eq!(e.matches("tmc study runs on one process").count(), 1, "{e}");
    assert!(!dir.join("study-out").exists());
}

/// `mpirun -n ranks tmc solve CASE -q -o OUT extra…` started in a process group of its own
/// (mpirun and its ranks), returned once the run has written step `step`.
fn mpirun_job(
    ranks: usize,
    case: &Path,
    out: &Path,
    extra: &[&str],
    step: usize,
) -> std::process::Child {
    mpirun_job_until(
        ranks,
        case,
        out,
        extra,
        &[],
        &format!("step_{step:04}.pvtu"),
    )
}

/// As [`mpirun_job`] with the environment `env` added, returned once the file `until` is in
/// OUT.
fn mpirun_job_until(
    ranks: usize,
    case: &Path,
    out: &Path,
    extra: &[&str],
    env: &[(&str, &str)],
    until: &str,
) -> std::process::Child {
    use std::os::unix::process::CommandExt;
    let job = common::mpirun_command(ranks)
        .envs(env.iter().copied())
        .arg("solve")
        .arg(case)
        .args(["-q", "-o"])
        .arg(out)
        .args(extra)
        .process_group(0)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let file = out.join(until);
    let t0 = std::time::Instant::now();
    while !file.exists() {
        assert!(t0.elapsed().as_secs() < 300, "no {}", file.display());
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    job
}

/// As [`mpirun_job`], stopped once its step `step` is written by SIGINT to each rank, what
/// mpirun sends them on a Ctrl-C: sent to the ranks themselves, since Open MPI puts each in a
/// process group of its own and mpirun's forwarding was seen to come after the run's end once
/// in four runs on a loaded machine (issue 70).
fn mpirun_interrupted(
    ranks: usize,
    case: &Path,
    out: &Path,
    extra: &[&str],
    step: usize,
) -> std::process::Output {
    let job = mpirun_job(ranks, case, out, extra, step);
    let ranks_of_job = children(job.id());
    assert!(!ranks_of_job.is_empty(), "the job's ranks");
    for pid in ranks_of_job {
        unsafe { libc::kill(pid as i32, libc::SIGINT) };
    }
    job.wait_with_output().unwrap()
}

/// Ctrl-C to `mpirun` itself, as a terminal sends it: Open MPI 4.1 sends the ranks SIGTERM a
/// second later and kills them a second after that, before a step of the 20.5k row (about
/// 2 s on two ranks here) can end. The run still ends as an interrupted run does: at its last
/// accepted step, with `summary.json` saying so, its history and its checkpoint as long, and
/// no lock left (issue 70, item 6).
#[test]
fn ctrl_c_to_mpirun_mid_step_ends_at_the_last_accepted_step_with_its_summary() {
    let dir = common::scratch("dist-ctrl-c-mpirun");
    let case = root().join("cases/block-plate-3d-tm1.toml");
    let out = dir.join("run");
    let params = [
        "--set",
        "mesh_options.params={ n = 16, nb = 10, nm = 1, nq = 6 }",
    ];
    // the first step written, the second under way
    let job = mpirun_job(2, &case, &out, &params, 1);
    unsafe { libc::kill(job.id() as i32, libc::SIGINT) };
    let o = job.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("interrupted at λ"), "{err}");
    let s = common::summary(&out);
    let message = s["message"].as_str().unwrap();
    assert!(message.starts_with("interrupted"), "{message}");
    let steps = s["load_steps"].as_u64().unwrap() as usize;
    assert!(steps >= 1, "{message}");
    let (_, rows) = common::history(&out);
    assert_eq!(
        rows.len(),
        steps + 1,
        "one history row per step the summary counts"
    );
    assert!(!out.join(".tmc.lock").exists(), "the lock is left");
    // the checkpoint is of the same step, for --restart
    let restart = std::fs::read_to_string(out.join("restart.json")).unwrap();
    let restart: serde_json::Value = serde_json::from_str(&restart).unwrap();
    assert_eq!(restart["accepted"].as_u64(), Some(steps as u64));
}

/// The 20.5k row rerun on two ranks (`extra` after its mesh) into a folder that holds a
/// finished run of the scene on a coarse mesh, stopped by Ctrl-C to `mpirun` once the file
/// `until` is in the folder: the rerun fails, the folder is byte for byte as the coarse run
/// left it (no lock), and the rerun's stderr is returned.
fn rerun_stopped_early(tag: &str, extra: &[&str], until: &str) -> String {
    let fine = "mesh_options.params={ n = 16, nb = 10, nm = 1, nq = 6 }";
    rerun_stopped_early_on(tag, &[&["--set", fine][..], extra].concat(), &[], until)
}

/// As [`rerun_stopped_early`], the rerun given `params` and the environment `env`.
fn rerun_stopped_early_on(tag: &str, params: &[&str], env: &[(&str, &str)], until: &str) -> String {
    let dir = common::scratch(tag);
    let case = root().join("cases/block-plate-3d-tm1.toml");
    let out = dir.join("run");
    let o = solve_cli(&case, &out, &["--set", COARSE]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = folder_files(&out);
    let job = mpirun_job_until(2, &case, &out, params, env, until);
    unsafe { libc::kill(job.id() as i32, libc::SIGINT) };
    let o = job.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{err}");
    same_files(&folder_files(&out), &before, &err);
    err
}

/// The block on the plate meshed coarsely: a run of seconds.
const COARSE: &str = "mesh_options.params={ n = 4, nb = 2, nm = 1, nq = 2 }";

/// Records that take `RECORDS_DELAY` after their new files are written (a slow disk): longer
/// than `mpirun` waits after Ctrl-C.
const SLOW_RECORDS: [(&str, &str); 1] = [("TMC_RECORDS_DELAY_MS", "3000")];

/// Ctrl-C to `mpirun` while a rerun takes its first step: the launcher ends the ranks before
/// the step can, and the folder is as the previous run left it, with no lock, and the run
/// says so (issue 70, items 5 and 6; before, the lock stayed and the previous results waited
/// aside for the next run to put them back).
#[test]
fn ctrl_c_to_mpirun_before_the_first_step_leaves_the_previous_results_as_they_were() {
    // on two ranks the steps are written as .pvtu: the rerun's own initial state; its first
    // step, of Δλ = 0.45, takes about a dozen Newton iterations, seconds past mpirun's
    let err = rerun_stopped_early(
        "dist-ctrl-c-first",
        &["--set", "steps.initial=0.45"],
        "step_0000.pvtu",
    );
    assert!(err.contains("interrupted at λ"), "{err}");
    assert!(err.contains("after 0 converged steps"), "{err}");
    assert!(err.contains("keeps the previous run's results"), "{err}");
}

/// Ctrl-C to `mpirun` while a rerun sets up (meshing, the model, the solver's analysis, before
/// its initial state is recorded): the folder is as the previous run left it, with no lock
/// (issue 70, item 6; before, the lock stayed and the previous results waited aside).
#[test]
fn ctrl_c_to_mpirun_while_a_rerun_sets_up_leaves_the_previous_results_as_they_were() {
    // the rerun's setup, from its lock to its initial state's files, takes about 5 s here:
    // past mpirun's second
    let err = rerun_stopped_early("dist-ctrl-c-setup", &[], ".tmc.lock");
    assert!(
        err.contains("interrupted before its first step") && err.contains("keeps the previous"),
        "{err}"
    );
}

/// Ctrl-C to `mpirun` while a rerun records its first step, on a disk slower than the second
/// `mpirun` waits: the step's files already written are taken back, and the folder is as the
/// previous run left it, with no lock (issue 70, item 6; before, the rank was killed while it
/// recorded, its lock and the step's files left, the previous results aside).
#[test]
fn ctrl_c_to_mpirun_while_a_rerun_records_its_first_step_leaves_the_previous_results() {
    let params = ["--set", COARSE];
    let err = rerun_stopped_early_on(
        "dist-ctrl-c-records",
        &params,
        &SLOW_RECORDS,
        "step_0001.pvtu",
    );
    assert!(err.contains("keeps the previous run's results"), "{err}");
}

/// Ctrl-C to `mpirun` while a step is recorded on a slow disk: the run ends at the step before,
/// none of the step's files left; and a restart stopped so before its first step leaves the
/// folder as it was, to be restarted again (issue 70, item 6).
#[test]
fn ctrl_c_to_mpirun_while_a_step_is_recorded_ends_at_the_step_before_and_restarts() {
    let dir = common::scratch("dist-ctrl-c-recording");
    let case = root().join("cases/block-plate-3d-tm1.toml");
    let out = dir.join("run");
    let params = ["--set", COARSE];
    let stop = |extra: &[&str], until: &str| {
        let job = mpirun_job_until(2, &case, &out, extra, &SLOW_RECORDS, until);
        unsafe { libc::kill(job.id() as i32, libc::SIGINT) };
        let o = job.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "{err}");
        assert!(!out.join(".tmc.lock").exists(), "the lock is left: {err}");
        err
    };
    // the second step's files under way
    let err = stop(&params, "step_0002.pvtu");
    assert!(err.contains("interrupted at λ"), "{err}");
    let s = common::summary(&out);
    assert_eq!(s["load_steps"].as_u64(), Some(1), "{err}");
    let (_, rows) = common::history(&out);
    assert_eq!(rows.len(), 2, "one history row per step the summary counts");
    let restart = std::fs::read_to_string(out.join("restart.json")).unwrap();
    let restart: serde_json::Value = serde_json::from_str(&restart).unwrap();
    assert_eq!(restart["accepted"].as_u64(), Some(1));
    let files = folder_files(&out);
    for name in files.keys() {
        assert!(
            !name.starts_with("step_0002") && !name.ends_with(".part"),
            "{name} left: {err}"
        );
    }
    let pvd = String::from_utf8_lossy(&files["block-plate-3d-tm1.pvd"]).into_owned();
    assert!(
        pvd.contains("step_0001.pvtu") && !pvd.contains("step_0002"),
        "{pvd}"
    );
    // a restart stopped as it records its first step: the folder as it was
    let err = stop(&[&params[..], &["--restart"]].concat(), "step_0002.pvtu");
    assert!(err.contains("to continue with --restart"), "{err}");
    same_files(&folder_files(&out), &files, &err);
    let o = mpirun(2, &case, &out, &[&params[..], &["--restart"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let s = common::summary(&out);
    let (_, rows) = common::history(&out);
    assert_eq!(rows.len() as u64, s["load_steps"].as_u64().unwrap() + 1);
}

/// The history of the run in `out` is that of the uninterrupted run in `full`: as many rows,
/// every physical column within 1e-10 of its largest value over the run (a column at
/// round-off, a sideways reaction, is judged against it), the same steps and iterations, the
/// same totals to 1e-10 (null in both where the scene has none). The residuals and Krylov
/// counts are the engines' own, and not judged.
fn same_history(full: &Path, out: &Path, label: &str) {
    let ((cols, expected), (cols2, rows)) = (common::history(full), common::history(out));
    assert_eq!(cols, cols2, "{label}");
    assert_eq!(rows.len(), expected.len(), "{label}: rows");
    let solver_own = [
        "res_u",
        "res_theta",
        "res_p",
        "krylov_iterations",
        "wall_seconds",
    ];
    for j in (0..cols.len()).filter(|&j| !solver_own.contains(&cols[j].as_str())) {
        let scale = expected.iter().map(|r| r[j].abs()).fold(0.0, f64::max);
        for (i, (a, b)) in expected.iter().zip(&rows).enumerate() {
            assert!(
                (a[j] - b[j]).abs() <= 1e-10 * scale || (a[j].is_nan() && b[j].is_nan()),
                "{label}, row {i}, {}: {} vs {}",
                cols[j],
                a[j],
                b[j]
            );
        }
    }
    let (a, b) = (summary(full), summary(out));
    for key in ["load_steps", "rejected_steps", "newton_iterations"] {
        assert_eq!(a[key], b[key], "{label}: {key}");
    }
    let totals = [
        "friction_work",
        "friction_heat",
        "heat_stored",
        "kinetic_energy",
        "energy",
    ];
    for key in totals {
        match (a[key].as_f64(), b[key].as_f64()) {
            (Some(x), Some(y)) => assert!(
                (x - y).abs() <= 1e-10 * x.abs(),
                "{label}: {key} {x} vs {y}"
            ),
            // what the scene does not have is null in both
            (x, y) => assert!(x.is_none() && y.is_none(), "{label}: {key} {x:?} vs {y:?}"),
        }
    }
}

/// `cases/friction-heating.toml` in steps twice as long (39 steps, against 79), written into
/// `dir`: a stop and a restart, and what they must give, are the same in any steps.
fn friction_heating_in_longer_steps(dir: &Path) -> PathBuf {
    let text = common::shipped_case("friction-heating");
    assert_eq!(text.matches("dt = 0.025\n").count(), 1);
    let case = dir.join("case.toml");
    std::fs::write(&case, text.replace("dt = 0.025\n", "dt = 0.05\n")).unwrap();
    case
}

#[test]
fn a_distributed_run_restarts_on_as_many_ranks_or_on_others() {
    // friction with its heat: history per point in two kinds of blocks (the stored θ and the
    // slip), each rank holding its own cells'. Stopped by Ctrl-C on two ranks, then continued
    // on two, one and three: the history of the uninterrupted two-rank run, the same steps and
    // iterations, every physical column to 1e-10 of its largest value (the residuals and
    // Krylov counts are the engines' own)
    let dir = scratch("distributed-restart");
    let case = friction_heating_in_longer_steps(&dir);
    let full = dir.join("full");
    let o = mpirun(2, &case, &full, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    // stopped three quarters of the way: the restarts take the rest
    let all_rows = common::history(&full).1;
    let stopped = dir.join("stopped");
    let o = mpirun_interrupted(2, &case, &stopped, &[], 3 * (all_rows.len() - 1) / 4);
    assert!(!o.status.success(), "the run was interrupted");
    let done = common::history(&stopped).1.len();
    assert!(
        done >= 3 && done < all_rows.len(),
        "stopped after {done} of {} rows",
        all_rows.len()
    );
    let copy = |from: &Path, to: &str| {
        let to = dir.join(to);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
        to
    };
    let (on_one, on_three) = (copy(&stopped, "on-one"), copy(&stopped, "on-three"));
    let restart = ["--restart"];
    for (ranks, out) in [(2, &stopped), (1, &on_one), (3, &on_three)] {
        let o = if ranks == 1 {
            solve_cli(&case, out, &restart)
        } else {
            mpirun(ranks, &case, out, &restart)
        };
        assert!(o.status.success(), "{ranks} ranks: {}", stderr(&o));
        same_history(&full, out, &format!("restarted on {ranks} ranks"));
    }
    // and what cannot be continued is said once, every rank ending with it, the folder as it
    // was: no run there, a finished run, a changed case, another case, a damaged checkpoint,
    // a damaged history (each in a folder of its own: the jobs run together)
    let other = root().join("cases/block-transient.toml");
    std::fs::write(on_one.join("restart.json"), "{").unwrap();
    let history = on_three.join("history.csv");
    let mut cut = std::fs::read(&history).unwrap();
    cut.truncate(cut.len() / 2);
    std::fs::write(&history, &cut).unwrap();
    let mut cp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(on_three.join("restart.json")).unwrap())
            .unwrap();
    // (made to look unfinished and sealed again, so that the history is what is judged)
    cp["t"] = 1.25.into();
    cp.as_object_mut().unwrap().remove("seal");
    let sealed = tmc::driver::checkpoint::seal(&cp.to_string());
    std::fs::write(on_three.join("restart.json"), sealed).unwrap();
    let k = ["--restart", "--set", "region.solid.k=2.0"];
    let nothing = dir.join("nothing");
    std::fs::create_dir_all(&nothing).unwrap();
    let (changed, other_case) = (copy(&full, "changed"), copy(&full, "other-case"));
    let refused = [
        (&case, &nothing, &restart[..], "has no restart.json"),
        (&case, &full, &restart[..], "has finished"),
        (
            &case,
            &changed,
            &k[..],
            "has changed since: region[0].k: 1.0 then, 2.0 now",
        ),
        (&other, &other_case, &restart[..], "has changed since"),
        (&case, &on_one, &restart[..], "does not begin with its seal"),
        (
            &case,
            &on_three,
            &restart[..],
            "history.csv does not go with it",
        ),
    ];
    let before: Vec<_> = refused.iter().map(|r| folder_files(r.1)).collect();
    let jobs: Vec<_> = (refused.iter())
        .map(|&(case, out, args, _)| (2, solve_args(case, out, args)))
        .collect();
    for (i, o) in mpirun_together(&jobs).into_iter().enumerate() {
        let (_, out, _, says) = refused[i];
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{says}: {e}");
        assert_eq!(e.matches(says).count(), 1, "{says}: {e}");
        assert!(
            !e.contains("MPI_ERR") && !e.contains("panicked"),
            "{says}: {e}"
        );
        assert_eq!(folder_files(out), before[i], "{says}: the folder as it was");
    }
}

#[test]
fn a_drag_with_inertia_is_the_same_on_two_ranks_and_restarts_across_them() {
    // inertia's history (u and v per point) is held by the rank that owns the cell and
    // gathered into the checkpoint cell by cell. The pad with one cell across at μ = 0.5,
    // which passes its slip event only with a mass, dragged 0.5: on two ranks the serial
    // run's steps, iterations, state and kinetic energy; stopped by Ctrl-C on two ranks and
    // continued on two and on one, the uninterrupted two-rank history
    // (a `.vtu` every step: the run is stopped once a step's is written)
    let text = crate::friction::with_mass(&crate::friction::pad_case(Some(0.5), 0.5), 1e-4)
        .replace(common::ENDS_ONLY, "");
    let options = "params = { n = 16, m = 8, l = 1 }";
    let case = common::case_file("distributed-inertia", "pad.geo", options, &text);
    let dir = case.parent().unwrap();
    let (serial, full) = (dir.join("serial"), dir.join("full"));
    let o = solve_cli(&case, &serial, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = mpirun(2, &case, &full, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (summary(&serial), summary(&full));
    assert_eq!(b["ranks"], 2);
    for key in ["load_steps", "rejected_steps", "newton_iterations"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    same_field(&last_step(&serial), &last_step(&full), "u", "on two ranks");
    // the contact shear too: a friction cell's slip plane is known to its own rank only, and
    // a node on the cut is in both parts with the same value
    for field in ["contact_pressure", "contact_shear"] {
        same_field(
            &last_step(&serial),
            &last_step(&full),
            field,
            "on two ranks",
        );
    }
    for key in ["kinetic_energy", "friction_work"] {
        let (p, q) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
        assert!(p > 0.0 && (p - q).abs() <= 1e-8 * p, "{key}: {p} vs {q}");
    }
    let stopped = dir.join("stopped");
    let all = common::history(&full).1.len();
    let o = mpirun_interrupted(2, &case, &stopped, &[], 3 * (all - 1) / 4);
    assert!(!o.status.success(), "the run was interrupted");
    let done = common::history(&stopped).1.len();
    assert!(
        done >= 3 && done < all,
        "stopped after {done} of {all} rows"
    );
    let on_one = dir.join("on-one");
    std::fs::create_dir_all(&on_one).unwrap();
    for e in std::fs::read_dir(&stopped).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), on_one.join(e.file_name())).unwrap();
    }
    for (ranks, out) in [(2, &stopped), (1, &on_one)] {
        let o = if ranks == 1 {
            solve_cli(&case, out, &["--restart"])
        } else {
            mpirun(ranks, &case, out, &["--restart"])
        };
        assert!(o.status.success(), "{ranks} ranks: {}", stderr(&o));
        same_history(
            &full,
            out,
            &format!("with inertia, restarted on {ranks} ranks"),
        );
    }
}

/// A process's state letter and its parent's pid, from /proc/PID/stat (`None` once it is gone).
fn proc_stat(pid: u32) -> Option<(String, u32)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // pid (comm) state ppid …: the comm may hold spaces, so count from its last ')'
    let mut after = stat.rsplit_once(')')?.1.split_whitespace();
    Some((after.next()?.to_string(), after.next()?.parse().ok()?))
}

/// The processes whose parent is `parent` (from /proc).
fn children(parent: u32) -> Vec<u32> {
    std::fs::read_dir("/proc")
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|&pid| proc_stat(pid).is_some_and(|(_, ppid)| ppid == parent))
        .collect()
}

#[test]
fn a_rank_killed_mid_run_leaves_every_file_whole_and_the_run_restarts() {
    // kill -9 of one rank after step 20 (mpirun then ends the job): no file of the results
    // cut short under its own name, and --restart on two ranks gives the uninterrupted history
    let dir = scratch("distributed-kill");
    let case = friction_heating_in_longer_steps(&dir);
    let full = dir.join("full");
    assert!(mpirun(2, &case, &full, &[]).status.success());
    for victim in ["0", "1"] {
        let out = dir.join(format!("killed-{victim}"));
        let mut job = mpirun_job(2, &case, &out, &[], 20);
        let t0 = std::time::Instant::now();
        let ranks = children(job.id());
        let rank = ranks.iter().copied().find(|pid| {
            let env = std::fs::read(format!("/proc/{pid}/environ")).unwrap_or_default();
            env.split(|&b| b == 0)
                .any(|v| v == format!("OMPI_COMM_WORLD_RANK={victim}").as_bytes())
        });
        let rank = rank.expect("the rank's process");
        unsafe { libc::kill(rank as i32, libc::SIGKILL) };
        assert!(
            !job.wait().unwrap().success(),
            "the job ended with its rank"
        );
        // until the job's other rank is gone too (it holds the folder until then)
        let alive =
            |pid: &u32| proc_stat(*pid).is_some_and(|(state, _)| state != "Z" && state != "X");
        while ranks.iter().any(alive) {
            assert!(t0.elapsed().as_secs() < 300, "the job's ranks stay");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        // every file under its own name whole (a file being written when the rank died is
        // under its .part name): every step file reads back
        for e in std::fs::read_dir(&out).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            if name.ends_with(".pvtu") {
                step_points(&out.join(&name), "u");
            }
        }
        let o = mpirun(2, &case, &out, &["--restart"]);
        assert!(o.status.success(), "rank {victim} killed: {}", stderr(&o));
        // the restart wrote again what was being written: no .part left
        for e in std::fs::read_dir(&out).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            assert!(
                !name.ends_with(".part"),
                "rank {victim} killed: {name} left"
            );
        }
        same_history(&full, &out, &format!("rank {victim} killed"));
    }
}

#[test]
fn check_says_what_it_can_size_on_each_engine() {
    // faer's factor is laid out before the run; PETSc's only when it factorises, so the
    // memory `tmc check` gives on PETSc is the tangent's alone, and it says so
    let run = |extra: &[&str]| {
        let mut args = vec!["check", "cases/block.toml"];
        args.extend(extra);
        let o = common::tmc(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let faer = run(&[]);
    assert!(
        faer.contains("entries; factor: ") && faer.contains("MB at the run's peak"),
        "{faer}"
    );
    let petsc = run(&["--set", "solver.engine=\"petsc\""]);
    assert!(
        petsc.contains("the factor is PETSc's, sized when it factorises")
            && petsc.contains("MB at the run's peak besides the factor"),
        "{petsc}"
    );
    // and which solver each engine will use: on PETSc, its own words for KSP and PC
    assert!(
        petsc.contains(
            "linear solver: mechanics: petsc preonly/cholesky; heat: petsc preonly/cholesky"
        ),
        "{petsc}"
    );
}

#[test]
fn check_under_mpirun_reports_once_with_each_rank_s_memory() {
    // before, every rank printed the whole report, each with its own part's tangent and no
    // rank named
    let case = root().join("cases/block.toml");
    let o = common::mpirun_tmc(2, &["check".as_ref(), case.as_os_str()]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(said.matches("ready to solve").count(), 1, "{said}");
    let ranks: Vec<(usize, f64)> = (0..2)
        .map(|r| {
            let line = said
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("rank {r}: ")))
                .unwrap_or_else(|| panic!("no line of rank {r} in {said}"));
            let words: Vec<&str> = line.split_whitespace().collect();
            // "rank R: E tangent entries, about M MB"
            (words[2].parse().unwrap(), words[6].parse().unwrap())
        })
        .collect();
    let total: usize = said
        .lines()
        .find_map(|l| l.strip_prefix("tangent: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no tangent line in {said}"));
    assert!(said.contains("entries over 2 ranks"), "{said}");
    assert_eq!(ranks[0].0 + ranks[1].0, total, "{said}");
    // each rank holds a part: more than none, less than the whole, and some memory for it
    for (entries, mb) in ranks {
        assert!(entries > 0 && entries < total && mb > 0.0, "{said}");
    }
}

#[test]
fn a_reconnected_friction_layer_is_refused_on_several_ranks_with_the_folder_kept() {
    let text = crate::friction::pad_case(Some(0.3), 0.5)
        .replace("normal = [0, 1] }", "normal = [0, 1], reconnect = true }");
    let options = "params = { n = 16, m = 8, l = 1 }";
    let case = common::case_file("distributed-reconnect", "pad.geo", options, &text);
    let out = case.with_file_name("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("mine.txt"), "kept").unwrap();
    let o = mpirun(2, &case, &out, &[]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert_eq!(e.matches("runs on one process").count(), 1, "{e}");
    assert_eq!(
        std::fs::read_to_string(out.join("mine.txt")).unwrap(),
        "kept"
    );
    // and `tmc check` under mpirun refuses it as the solve does
    let c = common::mpirun_tmc(2, &["check".as_ref(), case.as_os_str()]);
    let e = stderr(&c);
    assert!(!c.status.success(), "{e}");
    assert_eq!(e.matches("runs on one process").count(), 1, "{e}");
}

/// `[solver]` keys that conflict are reported at the key's own line, not at the file's first.
#[test]
fn a_linear_solver_on_the_petsc_engine_is_refused_at_its_line() {
    let text = case_body("block") + "\n[solver]\nengine = \"petsc\"\nlinear = \"lu\"\n";
    let case = case_file("solver-lines", "block.geo", "", &text);
    let written = std::fs::read_to_string(&case).unwrap();
    let line = 1 + written
        .lines()
        .position(|l| l == "linear = \"lu\"")
        .unwrap();
    for o in [
        tmc(&["check", case.to_str().unwrap()]),
        solve_cli(&case, &case.with_file_name("out"), &[]),
    ] {
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(
            e.contains(&format!("case.toml:{line}:"))
                && e.contains("[solver] linear chooses faer's solvers"),
            "line {line}: {e}"
        );
    }
}
