//! One test per class of bad or hostile input, end to end through the `tmc` binary: no panic,
//! no exit 0 without output, no lost file, a message that names the file, line, key, group,
//! element or body, and singular systems found before solving.

use crate::common;

use common::{history, root, scratch, stderr as err, tmc, tmc_with as tmc_env};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A failed run: exit status 1, a message, and no panic.
fn fails_with(o: &Output, words: &[&str]) -> String {
    let e = err(o);
    assert!(!o.status.success(), "should fail: {e}");
    assert_eq!(o.status.code(), Some(1), "an error, not a crash: {e}");
    assert!(!e.contains("panicked"), "{e}");
    for w in words {
        assert!(e.contains(w), "\"{w}\" not in: {e}");
    }
    e
}

/// `case` solved into `out` is refused with `words` in the message, none of serde's own words
/// for a shape (its type names), and nothing written; `tmc check` refuses it with the same
/// words (check is the promise that a solve starts).
fn refused(case: &Path, out: &Path, tag: &str, words: &[&str]) {
    checked_alike(case, words);
    let e = fails_with(&solve(case, out), words);
    assert!(
        !e.contains("untagged") && !e.contains("struct"),
        "{tag}: {e}"
    );
    assert!(
        !out.join("step_0000.vtu").exists(),
        "{tag}: nothing written: {e}"
    );
}

/// `tmc check CASE` refuses `case` with `words`, as `solve` did (check is the promise that a
/// solve starts: issue 70, item 1).
fn checked_alike(case: &Path, words: &[&str]) {
    fails_with(&tmc(&["check", case.to_str().unwrap()]), words);
}

/// Each case `(tag, body, words)` on the slab, in `dir`, [`refused`].
fn each_refused(dir: &Path, cases: Vec<(&str, String, Vec<&str>)>) {
    let out = dir.join("out");
    for (tag, body, words) in cases {
        refused(
            &slab_case(dir, &format!("{tag}-c"), &body),
            &out,
            tag,
            &words,
        );
    }
}

/// `cases` with the slab's mechanical conditions [`HELD`] after each body.
fn with_held<'a>(
    cases: Vec<(&'a str, String, Vec<&'a str>)>,
) -> Vec<(&'a str, String, Vec<&'a str>)> {
    (cases.into_iter())
        .map(|(tag, body, words)| (tag, body + HELD, words))
        .collect()
}

/// The slab (2 × 1, groups solid, left, right, top, bottom, origin) with `body` after its
/// `mesh` line.
fn slab_case(dir: &Path, name: &str, body: &str) -> PathBuf {
    slab_case_params(dir, name, "n = 4, m = 2", body)
}

/// As [`slab_case`], meshed with the `.geo` parameters `params`.
fn slab_case_params(dir: &Path, name: &str, params: &str, body: &str) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(
        &p,
        format!(
            "mesh = \"{}\"\n[mesh_options]\nparams = {{ {params} }}\n{body}",
            root().join("geo/slab.geo").display()
        ),
    )
    .unwrap();
    p
}

const SOLID: &str = "[[region]]\ngroup = \"solid\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0\n";
const HELD: &str = "[[bc]]\ngroup = \"left\"\nux = 0.0\n[[bc]]\ngroup = \"origin\"\nuy = 0.0\n[[bc]]\ngroup = \"right\"\nux = 0.2\n";

fn solve(case: &Path, out: &Path) -> Output {
    common::solve_cli(case, out, &[])
}

/// A scratch folder `name` holding a slab case "good" solved into its folder "out": the
/// folder, that output folder, the case, and the output's files with their bytes.
fn finished_run(name: &str) -> (PathBuf, PathBuf, PathBuf, Vec<(String, Vec<u8>)>) {
    let dir = scratch(name);
    let out = dir.join("out");
    let good = slab_case(&dir, "good", &format!("{SOLID}{HELD}"));
    assert!(solve(&good, &out).status.success());
    let before = contents(&out);
    (dir, out, good, before)
}

/// Each file in `dir` with its bytes, by name.
fn contents(dir: &Path) -> Vec<(String, Vec<u8>)> {
    (listing(dir).into_iter())
        .map(|f| (f.clone(), std::fs::read(dir.join(&f)).unwrap()))
        .collect()
}

/// File names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn what_used_to_panic_now_ends_in_an_error() {
    let dir = scratch("bad-panic");
    // one solid region and nothing else: chunks_exact(0) in the assembly before
    let case = slab_case(&dir, "nothing", SOLID);
    fails_with(
        &solve(&case, &dir.join("out")),
        &["nothing.toml:1", "loads nothing"],
    );
    checked_alike(&case, &["nothing.toml:1", "loads nothing"]);
    // a history row shorter than its header: indexed past its end before
    let res = dir.join("short");
    std::fs::create_dir_all(&res).unwrap();
    std::fs::write(res.join("history.csv"), "lambda,gap\n0,1\n0.5\n").unwrap();
    fails_with(
        &tmc(&["plot", res.to_str().unwrap(), "-c", "gap"]),
        &["history.csv", "line 3: 1 fields, but the header has 2"],
    );
    assert!(!res.join("gap.png").exists());
    // a probe whose name holds a comma: tmc's own history stays readable
    let case = slab_case(
        &dir,
        "comma",
        &format!("{SOLID}{HELD}[[probe]]\nname = \"u, right\"\nfield = \"ux\"\nat = [2.0, 1.0]\n"),
    );
    let out = dir.join("comma-out");
    let o = solve(&case, &out);
    assert!(o.status.success(), "{}", err(&o));
    let (cols, rows) = history(&out);
    assert!(cols.contains(&"u, right".to_string()), "{cols:?}");
    let c = cols.iter().position(|c| c == "u, right").unwrap();
    assert!((rows.last().unwrap()[c] - 0.2).abs() < 1e-12);
    let o = tmc(&["plot", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(out.join("u__right.png").is_file(), "{:?}", listing(&out));
}

#[test]
fn gmsh_exiting_or_a_full_disk_never_ends_in_success() {
    let dir = scratch("bad-exit0");
    // the usual batch ending of a .geo: gmsh's exit() used to end tmc with status 0
    let geo = dir.join("batch.geo");
    let text = std::fs::read_to_string(root().join("geo/slab.geo")).unwrap();
    std::fs::write(
        &geo,
        format!("{text}\nMesh 2;\nSave \"batch-own.msh\";\nExit;\n"),
    )
    .unwrap();
    let msh = dir.join("batch.msh");
    fails_with(
        &tmc(&["mesh", geo.to_str().unwrap(), "-o", msh.to_str().unwrap()]),
        &["batch.geo", "Exit"],
    );
    assert!(!msh.exists() && !dir.join("batch.part.msh").exists());
    let case = dir.join("batch.toml");
    std::fs::write(&case, format!("mesh = \"batch.geo\"\n{SOLID}{HELD}")).unwrap();
    let out = dir.join("batch-out");
    fails_with(&solve(&case, &out), &["batch.geo", "Exit"]);
    checked_alike(&case, &["batch.geo", "Exit"]);
    assert!(!out.join("summary.json").exists());

    // a full disk, as a file size limit: every write checked, no truncated file left under
    // its final name (SIGXFSZ ignored, so writes fail with EFBIG as on a full disk)
    let limited = |args: &str| {
        Command::new("sh")
            .arg("-c")
            .arg(format!(
                "trap '' XFSZ; ulimit -f 24; exec {} {args}",
                env!("CARGO_BIN_EXE_tmc")
            ))
            .current_dir(root())
            .output()
            .unwrap()
    };
    let big = dir.join("big.msh");
    let o = limited(&format!(
        "mesh geo/slab.geo --set n=60 --set m=30 -o {}",
        big.display()
    ));
    fails_with(&o, &["slab.geo", "cannot be read back", "truncated"]);
    assert!(
        !big.exists() && !dir.join("big.part.msh").exists(),
        "{:?}",
        listing(&dir)
    );
    let block = dir.join("block.msh");
    common::mesh_cli("geo/block.geo", &block);
    let body = std::fs::read_to_string(root().join("cases/block.toml")).unwrap();
    let case = dir.join("block.toml");
    std::fs::write(&case, body.replace("../geo/block.geo", "block.msh")).unwrap();
    // over a first run's results: the rerun fails on its first file, before its first step,
    // and puts them back as they were
    let out = dir.join("full");
    let o = solve(&case, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = contents(&out);
    let o = limited(&format!("solve {} -o {} -q", case.display(), out.display()));
    let e = fails_with(&o, &["cannot write"]);
    assert!(e.contains("File too large") || e.contains("space"), "{e}");
    for f in listing(&out) {
        assert!(!f.ends_with(".part"), "{f} left behind");
        if f.ends_with(".vtu") {
            vtkio::Vtk::import(out.join(&f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
    }
    assert!(
        before == contents(&out),
        "the first run's results as they were"
    );
    // into a new folder: it fails the same way and leaves no folder behind
    let fresh = dir.join("fresh");
    let o = limited(&format!(
        "solve {} -o {} -q",
        case.display(),
        fresh.display()
    ));
    fails_with(&o, &["cannot write"]);
    assert!(!fresh.exists(), "{:?}", listing(&fresh));
}

#[test]
fn nothing_a_user_wrote_is_lost() {
    let (dir, out, good, before) = finished_run("bad-loss");
    // a rerun with a misspelt group fails before touching the folder
    let typo = slab_case(
        &dir,
        "typo",
        &format!("{SOLID}{}", HELD.replace("\"left\"", "\"lefft\"")),
    );
    fails_with(&solve(&typo, &out), &["typo.toml", "lefft"]);
    checked_alike(&typo, &["typo.toml", "lefft"]);
    for (f, bytes) in &before {
        assert_eq!(&std::fs::read(out.join(f)).unwrap(), bytes, "{f} changed");
    }
    // files tmc did not write survive a rerun, even with tmc-like names
    for f in ["notes.txt", "mine.pvd", "step_9999.vtu", "history.csv.bak"] {
        std::fs::write(out.join(f), "mine").unwrap();
    }
    let shorter = slab_case(
        &dir,
        "good",
        &format!("{SOLID}{HELD}[steps]\nmax = 1.0\ninitial = 1.0\n"),
    );
    let o = solve(&shorter, &out);
    assert!(o.status.success(), "{}", err(&o));
    for f in ["notes.txt", "mine.pvd", "step_9999.vtu", "history.csv.bak"] {
        assert_eq!(std::fs::read_to_string(out.join(f)).unwrap(), "mine", "{f}");
    }
    // the previous run's later steps went with it
    let steps = common::history(&out).1.len() - 1;
    assert!(!out.join(format!("step_{:04}.vtu", steps + 1)).exists());
    assert!(
        !out.join(".tmc.lock").exists(),
        "the lock goes with the run"
    );

    // a folder another live run holds is refused; a lock of a dead process is taken over
    std::fs::write(out.join(".tmc.lock"), format!("{}\n", std::process::id())).unwrap();
    fails_with(
        &solve(&good, &out),
        &["in use by another tmc run", &std::process::id().to_string()],
    );
    std::fs::write(out.join(".tmc.lock"), "2147483646\n").unwrap();
    let o = solve(&good, &out);
    assert!(o.status.success(), "{}", err(&o));
    assert!(!out.join(".tmc.lock").exists());

    // an interrupted run says so, with the λ it reached, and every history row has its file
    let slow = dir.join("slow");
    let o = common::solve_interrupted(&root().join("cases/block.toml"), &slow);
    fails_with(&o, &["interrupted at λ"]);
    let s = common::summary(&slow);
    assert_eq!(s["converged"], false);
    assert!(
        s["message"].as_str().unwrap().contains("interrupted"),
        "{s}"
    );
    let lambda = s["lambda"].as_f64().unwrap();
    assert!(lambda > 0.0 && lambda < 1.0, "λ = {lambda}");
    let (cols, rows) = history(&slow);
    let l = cols.iter().position(|c| c == "lambda").unwrap();
    assert_eq!(rows.last().unwrap()[l], lambda);
    for k in 0..rows.len() {
        assert!(
            slow.join(format!("step_{k:04}.vtu")).is_file(),
            "row {k} without its file"
        );
    }
    assert!(!slow.join(".tmc.lock").exists());
}

#[test]
fn a_rerun_that_takes_no_load_step_keeps_the_previous_results() {
    // a first run, then a rerun into its folder that cannot take its first load step (two
    // Newton iterations allowed, no step below the first, no continuation): the folder stays
    // as it was, byte for byte, and the message says so
    let (dir, out, _, before) = finished_run("bad-no-step");
    assert!(before.iter().any(|(f, _)| f == "summary.json"));
    let stuck = slab_case(
        &dir,
        "stuck",
        &format!(
            "{SOLID}{HELD}[steps]\ninitial = 1.0\nmin = 0.9\nmax_iter = 2\ncontinuation = false\n"
        ),
    );
    let e = fails_with(&solve(&stuck, &out), &["load step from λ = 0"]);
    assert!(
        e.contains("no load step was taken") && e.contains("keeps the previous run's results"),
        "{e}"
    );
    assert!(
        before == contents(&out),
        "the previous run's results as they were"
    );
    // with no previous run, the stuck run's own summary is what the folder holds
    let fresh = dir.join("fresh");
    let e = fails_with(
        &solve(&stuck, &fresh),
        &["the 0 converged steps up to λ = 0"],
    );
    assert!(!e.contains("previous run"), "{e}");
    let s = common::summary(&fresh);
    assert_eq!(s["converged"], false);
    assert_eq!(s["load_steps"], 0);
}

#[test]
fn bad_values_are_named_by_file_line_and_key() {
    let dir = scratch("bad-values");
    let out = dir.join("out");
    let cases = vec![
        (
            "alpha",
            format!("{}alpha = inf\n{HELD}", SOLID),
            vec!["alpha-c.toml:9", "region[0].alpha = inf"],
        ),
        (
            "theta0",
            format!("{}theta0 = nan\n{HELD}", SOLID),
            vec!["theta0-c.toml:9", "region[0].theta0 = nan"],
        ),
        (
            "force",
            format!("{}body_force = [1e300, 0.0]\n{HELD}", SOLID),
            vec!["force-c.toml:9", "body_force[0]", "out of range"],
        ),
        (
            "dims",
            format!("{}body_force = [0.0, -1.0, 0.0]\n{HELD}", SOLID),
            vec![
                "dims-c.toml:9",
                "region[0] (\"solid\")",
                "body_force has 3 components; this mesh is 2D",
            ],
        ),
        (
            "value",
            format!("{SOLID}{}", HELD.replace("ux = 0.2", "ux = -inf")),
            vec!["value-c.toml:", "ux = -inf"],
        ),
    ];
    each_refused(&dir, cases);
    // .geo parameters: a NaN is named against the case, a misspelt name is refused
    let p = slab_case_params(&dir, "nan-param", "n = nan", &format!("{SOLID}{HELD}"));
    let words = ["nan-param.toml:3", "mesh_options.params.n = nan"];
    fails_with(&solve(&p, &out), &words);
    checked_alike(&p, &words);
    let p = slab_case_params(&dir, "typo-param", "nn = 2", &format!("{SOLID}{HELD}"));
    let words = ["slab.geo", "no parameter \"nn\"", "L, H, n, m"];
    fails_with(&solve(&p, &out), &words);
    checked_alike(&p, &words);
    fails_with(
        &tmc(&["mesh", "geo/slab.geo", "--set", "hx=0.3"]),
        &["no parameter \"hx\""],
    );
    let o = tmc(&["mesh", "geo/slab.geo", "--set", "n=nan"]);
    assert!(
        !o.status.success() && err(&o).contains("not a finite number"),
        "{}",
        err(&o)
    );
    // a truncated mesh is named by its section and line
    let good = dir.join("slab.msh");
    common::mesh_cli("geo/slab.geo", &good);
    let text = std::fs::read_to_string(&good).unwrap();
    let cut = dir.join("cut.msh");
    std::fs::write(&cut, &text[..text.find("$EndNodes").unwrap() - 10]).unwrap();
    let p = dir.join("cut.toml");
    std::fs::write(&p, format!("mesh = \"cut.msh\"\n{SOLID}{HELD}")).unwrap();
    fails_with(
        &solve(&p, &out),
        &["cut.msh", "section $Nodes opened at line", "truncated"],
    );
    checked_alike(
        &p,
        &["cut.msh", "section $Nodes opened at line", "truncated"],
    );
    // the smaller ones
    let uz = slab_case(
        &dir,
        "uz",
        &format!("{SOLID}{HELD}[[probe]]\nname = \"w\"\nfield = \"uz\"\nat = [1.0, 1.0]\n"),
    );
    fails_with(&solve(&uz, &out), &["uz.toml:", "z quantity in a 2D mesh"]);
    checked_alike(&uz, &["uz.toml:", "z quantity in a 2D mesh"]);
    let tiny = slab_case(
        &dir,
        "tiny",
        &format!("{SOLID}{HELD}[steps]\nmin = 1e-300\n"),
    );
    fails_with(&solve(&tiny, &out), &["tiny.toml:", "min = 1e-300"]);
    checked_alike(&tiny, &["tiny.toml:", "min = 1e-300"]);
    let long: Vec<String> = (0..200_000)
        .map(|k| format!("{}", k as f64 * 1e-5))
        .collect();
    let long = slab_case(
        &dir,
        "long",
        &format!("{SOLID}{HELD}[steps]\npath = [{}]\n", long.join(", ")),
    );
    fails_with(&solve(&long, &out), &["long.toml:", "at most 100000"]);
    checked_alike(&long, &["long.toml:", "at most 100000"]);
    fails_with(
        &tmc_env(
            &["solve", good.to_str().unwrap()],
            &[("RAYON_NUM_THREADS", "100000")],
        ),
        &["RAYON_NUM_THREADS=100000"],
    );
    std::fs::create_dir_all(dir.join("folder.geo")).unwrap();
    fails_with(
        &tmc(&["mesh", dir.join("folder.geo").to_str().unwrap()]),
        &["is a folder"],
    );
    // a case or a mesh where the .geo belongs: said, not a gmsh syntax error on line 1
    let msh = dir.join("made.msh");
    std::fs::write(&msh, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
    for (file, says) in [
        ("cases/block.toml", "is a case file, not a .geo file"),
        (msh.to_str().unwrap(), "is a mesh already, not a .geo file"),
    ] {
        let o = tmc(&["mesh", file, "-o", dir.join("named.msh").to_str().unwrap()]);
        fails_with(&o, &[file, says]);
        assert!(!dir.join("named.msh").exists() && !dir.join("named.part.msh").exists());
    }
    // -o DIR: the mesh goes into the folder, nothing half-written beside it
    let o = tmc(&["mesh", "geo/slab.geo", "-o", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(dir.join("slab.msh").is_file() && !dir.join("slab.part.msh").exists());
    let o = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.contains("group \"solid\" (2D)") && o.contains("nodes"),
        "{o}"
    );
    // plot: a missing column draws nothing
    let res = dir.join("plotted");
    assert!(
        solve(&slab_case(&dir, "p", &format!("{SOLID}{HELD}")), &res)
            .status
            .success()
    );
    fails_with(
        &tmc(&["plot", res.to_str().unwrap(), "-c", "energy,nosuch"]),
        &["no column \"nosuch\""],
    );
    assert!(!res.join("energy.png").exists());
}

#[test]
fn a_solid_law_s_keys_are_checked_by_file_line_and_key() {
    let dir = scratch("bad-law");
    let mr = "[[region]]\ngroup = \"solid\"\nkind = \"solid\"\nK = 20.0\nlaw = \"mooney-rivlin\"\n";
    let cases = vec![
        (
            "unknown",
            SOLID.replace("mu = 10.0", "law = \"ogden\""),
            vec![
                "unknown-c.toml",
                "line 8",
                "unknown variant `ogden`",
                "`neo-hooke` or `mooney-rivlin`",
            ],
        ),
        (
            "no-c10",
            format!("{mr}C01 = 1.0\n"),
            vec![
                "no-c10-c.toml:8",
                "region[0] (\"solid\")",
                "law \"mooney-rivlin\" needs `C10`",
            ],
        ),
        (
            "no-c01",
            format!("{mr}C10 = 1.0\n"),
            vec!["no-c01-c.toml:8", "needs `C01`"],
        ),
        (
            "negative",
            format!("{mr}C10 = 1.0\nC01 = -0.5\n"),
            vec!["negative-c.toml:10", "`C01` must be ≥ 0, got -0.5"],
        ),
        (
            "zero",
            format!("{mr}C10 = 0.0\nC01 = 1.0\n"),
            vec!["zero-c.toml:9", "`C10` must be positive, got 0"],
        ),
        (
            "mu",
            format!("{mr}C10 = 1.0\nC01 = 1.0\nmu = 3.0\n"),
            vec![
                "mu-c.toml:11",
                "`mu` is not a key of law \"mooney-rivlin\"",
                "`K`, `C10` and `C01`",
            ],
        ),
        (
            "c10",
            format!("{SOLID}C10 = 1.0\n"),
            vec!["c10-c.toml:9", "`C10` is not a key of law \"neo-hooke\""],
        ),
        (
            "medium",
            format!(
                "{SOLID}[[region]]\ngroup = \"solid\"\nkind = \"medium\"\ngamma = 1e-4\nlaw = \"mooney-rivlin\"\n"
            ),
            vec![
                "medium-c.toml:13",
                "region[1]",
                "`law` chooses a solid's law",
            ],
        ),
    ];
    each_refused(&dir, with_held(cases));
}

#[test]
fn radiation_needs_absolute_temperatures_and_says_so() {
    let dir = scratch("bad-radiation");
    let warm = SOLID.replace("mu = 10.0", "mu = 10.0\nk = 5.0\ntheta0 = 300.0");
    let held = "[[bc]]\ngroup = \"left\"\ntheta = 600.0\n";
    let radiating = |key: &str| {
        format!(
            "[[bc]]\ngroup = \"right\"\nradiation = {{ emissivity = 0.8, theta_inf = 300.0, sigma = 5.67e-8{key} }}\n"
        )
    };
    let cases = vec![
        (
            "emissivity",
            format!("{warm}{held}{}", radiating("").replace("0.8", "1.5")),
            vec![
                "emissivity-c.toml:16",
                "`radiation.emissivity` must be in (0, 1], got 1.5",
            ],
        ),
        (
            "inf",
            format!("{warm}{held}{}", radiating("").replace("300.0,", "-20.0,")),
            vec![
                "inf-c.toml:16",
                "`radiation.theta_inf` must be positive",
                "kelvin",
            ],
        ),
        (
            "sigma",
            format!("{warm}{held}{}", radiating("").replace("5.67e-8", "0.0")),
            vec![
                "sigma-c.toml:16",
                "`radiation.sigma` must be positive",
                "SI",
            ],
        ),
        (
            "typo",
            format!("{warm}{held}{}", radiating(", eps = 1")),
            vec!["typo-c.toml", "line 16", "unknown field `eps`"],
        ),
        (
            "held",
            format!(
                "{warm}{held}{}",
                radiating("").replace("\"right\"", "\"left\"")
            ),
            vec![
                "held-c.toml:16",
                "the group radiates (`radiation`) here",
                "line 12",
            ],
        ),
        (
            // the slab starts at θ0 = 0: no absolute temperature
            "cold",
            format!(
                "{}{held}{}",
                SOLID.replace("mu = 10.0", "mu = 10.0\nk = 5.0"),
                radiating("")
            ),
            vec![
                "θ = 0.0000e0 ≤ 0",
                "boundary group \"right\", which radiates",
                "kelvin",
            ],
        ),
    ];
    each_refused(&dir, cases);
}

#[test]
fn a_medium_s_conductivity_keys_are_checked_by_file_line_and_key() {
    let dir = scratch("bad-conductivity");
    let medium = "[[region]]\ngroup = \"solid\"\nkind = \"medium\"\ngamma = 1e-2\n";
    let cases = vec![
        (
            "one-row",
            format!("{medium}k_table = [[1.0, 0.1]]\n"),
            vec![
                "one-row-c.toml:8",
                "region[0] (\"solid\"): `k_table` has 1 rows",
                "2 to 8",
            ],
        ),
        (
            "twice",
            format!("{medium}k_table = [[1.0, 0.1], [1.0, 0.2]]\n"),
            vec!["twice-c.toml:8", "gives J = 1 twice"],
        ),
        (
            "row",
            format!("{medium}k_table = [[1.0, 0.1], [0.0, 0.2]]\n"),
            vec!["row-c.toml:8", "row 1 is [0.0, 0.2]"],
        ),
        (
            "both",
            format!("{medium}k_table = [[1.0, 0.1], [0.1, 0.2]]\nk = 0.1\n"),
            vec![
                "both-c.toml:9",
                "`k` and `k_table` are two conductivity laws",
            ],
        ),
        (
            "no-thickness",
            format!("{medium}k = 0.1\nh_closed = 50.0\n"),
            vec!["no-thickness-c.toml:9", "`h_closed` needs `thickness`"],
        ),
        (
            "no-h",
            format!("{medium}k = 0.1\nthickness = 0.25\n"),
            vec!["no-h-c.toml:9", "give `h_closed` too"],
        ),
        (
            "negative",
            format!("{medium}k = 0.1\nh_closed = -5.0\nthickness = 0.25\n"),
            vec!["negative-c.toml:9", "`h_closed` must be positive, got -5"],
        ),
        (
            "solid",
            format!("{SOLID}h_closed = 5.0\n"),
            vec!["solid-c.toml:9", "`h_closed` is a medium key"],
        ),
        (
            "solid-table",
            format!("{SOLID}k = 1.0\nk_table = [[0.1, 1.0], [1.0, 2.0]]\n"),
            vec!["solid-table-c.toml:10", "`k_table` is a medium key"],
        ),
        (
            "solid-table-alone",
            format!("{SOLID}k_table = [[0.1, 1.0], [1.0, 2.0]]\n"),
            vec!["solid-table-alone-c.toml:9", "`k_table` is a medium key"],
        ),
    ];
    each_refused(&dir, with_held(cases));
}

#[test]
fn singular_systems_are_found_before_solving() {
    let dir = scratch("bad-singular");
    let out = dir.join("out");
    // held in x only
    let case = slab_case(
        &dir,
        "x-only",
        &format!(
            "{SOLID}[[bc]]\ngroup = \"left\"\nux = 0.0\n[[bc]]\ngroup = \"right\"\nux = 0.2\n"
        ),
    );
    let words = ["x-only.toml:1", "region \"solid\"", "move freely in y"];
    fails_with(&solve(&case, &out), &words);
    checked_alike(&case, &words);
    // held at one point in x and y: it can still turn
    let case = slab_case(
        &dir,
        "pinned",
        &format!(
            "{SOLID}[[bc]]\ngroup = \"origin\"\nux = 0.0\nuy = 0.0\n[[bc]]\ngroup = \"top\"\ntraction = [1.0, 0.0]\n"
        ),
    );
    fails_with(
        &solve(&case, &out),
        &["rotate freely about an axis along z"],
    );
    checked_alike(&case, &["rotate freely about an axis along z"]);
    // conduction with fluxes only: no temperature fixes the level
    let case = slab_case(
        &dir,
        "flux-only",
        &format!(
            "{SOLID}k = 1.0\n[[bc]]\ngroup = \"left\"\nheat_flux = 1.0\n[[bc]]\ngroup = \"right\"\nheat_flux = -1.0\n"
        ),
    );
    fails_with(
        &solve(&case, &out),
        &["temperature of the body", "not fixed"],
    );
    checked_alike(&case, &["temperature of the body", "not fixed"]);
    // a group without elements
    let good = dir.join("slab.msh");
    common::mesh_cli("geo/slab.geo", &good);
    let text = std::fs::read_to_string(&good).unwrap();
    let (head, rest) = text.split_once("$PhysicalNames\n").unwrap();
    let (count, names) = rest.split_once('\n').unwrap();
    let n: usize = count.trim().parse().unwrap();
    let ghost = format!("{head}$PhysicalNames\n{}\n1 77 \"ghost\"\n{names}", n + 1);
    std::fs::write(dir.join("ghost.msh"), ghost).unwrap();
    let p = dir.join("ghost.toml");
    std::fs::write(
        &p,
        format!("mesh = \"ghost.msh\"\n{SOLID}{HELD}[[bc]]\ngroup = \"ghost\"\nuy = 0.0\n"),
    )
    .unwrap();
    fails_with(
        &solve(&p, &out),
        &["ghost.toml:", "group \"ghost\" has no elements"],
    );
    checked_alike(&p, &["ghost.toml:", "group \"ghost\" has no elements"]);
    assert!(
        !out.exists(),
        "runs that fail on their input leave no folder behind"
    );
}

#[test]
fn studies_refuse_what_they_cannot_measure_or_keep_apart() {
    let dir = scratch("bad-study");
    let case = slab_case(
        &dir,
        "base",
        &format!("{SOLID}{HELD}[[probe]]\nname = \"u\"\nfield = \"ux\"\nat = [2.0, 1.0]\n"),
    );
    let study = |name: &str, head: &str, variants: &str| {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(
            &p,
            format!(
                "case = \"{}\"\nreference = \"last\"\n{head}\n{variants}",
                case.display()
            ),
        )
        .unwrap();
        tmc(&[
            "study",
            p.to_str().unwrap(),
            "-q",
            "-o",
            dir.join(name).to_str().unwrap(),
        ])
    };
    let one = "[[variant]]\nname = \"a\"\nset = { \"mesh_options.params.n\" = 2 }\n";
    fails_with(
        &study("measure", "measure = [\"nosuch\"]", one),
        &["no quantity \"nosuch\"", "u"],
    );
    fails_with(
        &study("column", "measure = [\"u\"]\nhistory = [\"nosuch\"]", one),
        &["no column \"nosuch\""],
    );
    assert!(!dir.join("column/history_nosuch.png").exists());
    fails_with(
        &study(
            "clash",
            "measure = [\"u\"]",
            "[[variant]]\nname = \"a b\"\n[[variant]]\nname = \"a_b\"\n",
        ),
        &["\"a b\" and \"a_b\"", "runs/a_b"],
    );
    fails_with(
        &study(
            "key",
            "measure = [\"u\"]",
            "[[variant]]\nname = \"k\"\nset = { \"region.solid.Kk\" = 2.0 }\n",
        ),
        &["variant \"k\"", "Kk"],
    );
}

#[test]
fn bad_friction_is_named_by_file_line_and_key() {
    let dir = scratch("bad-friction");
    let out = dir.join("out");
    let block = |name: &str, friction: &str, solid_friction: &str| {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(
            &p,
            format!(
                "mesh = \"{}\"\n[mesh_options]\nparams = {{ n = 4, m = 2, l = 1 }}\n\
                 [[region]]\ngroup = \"solid\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0\n{solid_friction}\n\
                 [[region]]\ngroup = \"medium\"\nkind = \"medium\"\ngamma = 1e-4\n{friction}\n\
                 [[bc]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\n\
                 [[bc]]\ngroup = \"top\"\nuy = -0.1\n",
                root().join("geo/block.geo").display()
            ),
        )
        .unwrap();
        p
    };
    for (tag, friction, solid, words) in [
        (
            "negative",
            "friction = { mu = -0.1, normal = [0, 1] }",
            "",
            vec![
                "negative.toml:14",
                "`friction.mu` must be finite and ≥ 0, got -0.1",
            ],
        ),
        (
            "nan",
            "friction = { mu = nan, normal = [0, 1] }",
            "",
            vec![
                "nan.toml:14",
                "`friction.mu` must be finite and ≥ 0, got NaN",
            ],
        ),
        (
            "zero-normal",
            "friction = { mu = 0.3, normal = [0, 0] }",
            "",
            vec!["zero-normal.toml:14", "`friction.normal`", "not all zero"],
        ),
        (
            "normal-3d",
            "friction = { mu = 0.3, normal = [0, 0, 1] }",
            "",
            vec![
                "normal-3d.toml:14",
                "`friction.normal` has 3 components; the mesh is 2D",
            ],
        ),
        (
            "fraction",
            "friction = { mu = 0.3, normal = [0, 1], heat_fraction = 1.5 }",
            "",
            vec![
                "fraction.toml:14",
                "`friction.heat_fraction` must be in [0, 1]",
            ],
        ),
        (
            "word",
            "friction = { mu = 0.3, normal = \"up\" }",
            "",
            vec![
                "word.toml:14",
                "`friction.normal` must be \"auto\" or a vector",
                "got \"up\"",
            ],
        ),
        (
            "normal-number",
            "friction = { mu = 0.3, normal = 5 }",
            "",
            vec![
                "normal-number.toml",
                "`normal` must be \"auto\" or the slip plane's normal as numbers",
            ],
        ),
        (
            "not-a-table",
            "friction = 0.3",
            "",
            vec![
                "not-a-table.toml",
                "expected a table such as { mu = 0.3, normal = [0, 1] }",
            ],
        ),
        (
            "typo",
            "friction = { mu = 0.3, normal = [0, 1], muu = 1 }",
            "",
            vec!["typo.toml", "muu"],
        ),
        (
            "forget-and-rejoin",
            "friction = { mu = 0.3, normal = [0, 1], reconnect = true, forget_slip = true }",
            "",
            vec![
                "forget-and-rejoin.toml:14",
                "`friction.forget_slip` cannot go with `friction.reconnect`",
            ],
        ),
        (
            "on-solid",
            "",
            "friction = { mu = 0.3, normal = [0, 1] }",
            vec![
                "on-solid.toml:9",
                "region[0] (\"solid\"): `friction`",
                "this region is a solid",
            ],
        ),
    ] {
        refused(&block(tag, friction, solid), &out, tag, &words);
    }
    // "auto" needs a solid surface: here the block is medium too
    let case = block("no-solid", "friction = { mu = 0.3, normal = \"auto\" }", "");
    let text = std::fs::read_to_string(&case).unwrap().replacen(
        "kind = \"solid\"\nK = 20.0\nmu = 10.0",
        "kind = \"medium\"\ngamma = 1e-4",
        1,
    );
    std::fs::write(&case, text).unwrap();
    let words = [
        "no-solid.toml:13",
        "region[1] (\"medium\")",
        "`friction.normal = \"auto\"`",
        "no solid region borders a medium region",
    ];
    let e = fails_with(&solve(&case, &out), &words);
    checked_alike(&case, &words);
    assert!(!out.join("step_0000.vtu").exists(), "nothing written: {e}");
}

#[test]
fn bad_time_keys_are_named_by_file_line_and_key() {
    // every [time] key of cases/block-transient.toml made bad in turn, through `tmc check`
    let dir = scratch("bad-time");
    let shipped = std::fs::read_to_string(root().join("cases/block-transient.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()));
    let table = "lambda = [[0.0, 0.0], [1.0, 1.0], [3.0, 1.0]]";
    let cases: &[(&str, &str, &str, &[&str])] = &[
        (
            "end-zero",
            "end = 3.0",
            "end = 0.0",
            &["`end` must be positive and finite, got 0"],
        ),
        (
            "end-negative",
            "end = 3.0",
            "end = -1.0",
            &["`end` must be positive"],
        ),
        (
            "dt-zero",
            "dt = 0.1",
            "dt = 0.0",
            &["`dt` must be positive and at most `end` (3), got 0"],
        ),
        (
            "dt-past-end",
            "dt = 0.1",
            "dt = 5.0",
            &["`dt` must be positive and at most `end`"],
        ),
        ("dt-nan", "dt = 0.1", "dt = nan", &["got NaN"]),
        (
            "dt-word",
            "dt = 0.1",
            "dt = \"fast\"",
            &["dt", "expected f64"],
        ),
        (
            "times-unsorted",
            "dt = 0.1",
            "dt = 0.1\ntimes = [2.0, 1.0]",
            &["`times` must increase within (0, end = 3]"],
        ),
        (
            "times-past-end",
            "dt = 0.1",
            "dt = 0.1\ntimes = [1.0, 4.0]",
            &["`times` must increase within (0, end = 3]"],
        ),
        (
            "lambda-unsorted",
            table,
            "lambda = [[0.0, 0.0], [3.0, 1.0], [1.0, 1.0]]",
            &["t increasing from 0"],
        ),
        (
            "lambda-late-start",
            table,
            "lambda = [[0.5, 0.0], [3.0, 1.0]]",
            &["t increasing from 0"],
        ),
        (
            "lambda-wide",
            table,
            "lambda = [[0.0, 0.0], [1.0, 1.0, 7.0], [3.0, 1.0]]",
            &["`lambda` row 2 has 3 values; each row is [t, λ]"],
        ),
        (
            "lambda-narrow",
            table,
            "lambda = [[0.0, 0.0], [1.0], [3.0, 1.0]]",
            &["`lambda` row 2 has 1 value;"],
        ),
        (
            "lambda-nan",
            table,
            "lambda = [[0.0, 0.0], [1.0, nan], [3.0, 1.0]]",
            &["finite [t, λ] rows"],
        ),
        (
            "capacity-negative",
            "rho_c = 400.0",
            "rho_c = -400.0",
            &["region[0] (\"solid\"): `rho_c` must be positive and finite, got -400"],
        ),
        (
            "density-zero",
            "rho_c = 400.0",
            "rho_c = 400.0\nrho = 0.0",
            &["region[0] (\"solid\"): `rho` must be positive and finite, got 0"],
        ),
        ("time-typo", "dt = 0.1", "dt = 0.1\ndtt = 0.2", &["dtt"]),
    ];
    for (name, old, new, words) in cases {
        assert!(shipped.contains(old), "{name}");
        let text = shipped.replacen(old, new, 1);
        let case = dir.join(format!("{name}.toml"));
        std::fs::write(&case, &text).unwrap();
        let first = new.lines().last().unwrap();
        let line = 1 + text.lines().position(|l| l == first).unwrap();
        let mut expect = vec![format!("{name}.toml:{line}")];
        if name.starts_with("dt-word") || name.starts_with("time-typo") {
            expect = vec![format!("{name}.toml")]; // TOML's own line and column
        }
        let mut all: Vec<&str> = expect.iter().map(|s| s.as_str()).collect();
        all.extend_from_slice(words);
        fails_with(&tmc(&["check", case.to_str().unwrap()]), &all);
    }
}

#[test]
fn what_was_accepted_without_a_word_is_refused() {
    let dir = scratch("bad-silent");
    let convection = std::fs::read_to_string(root().join("cases/slab-convection.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()));
    let write = |name: &str, text: &str| {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        p
    };
    // `tmc check` of a case that is accepted: what it prints, on stdout and stderr
    let checked = |case: &std::path::Path| {
        let o = tmc(&["check", case.to_str().unwrap()]);
        assert!(o.status.success(), "{}", err(&o));
        String::from_utf8_lossy(&o.stdout).to_string() + &err(&o)
    };
    let line_of = |text: &str, l: &str| 1 + text.lines().position(|x| x == l).unwrap();
    // convection on a group whose θ another [[bc]] holds: the held θ won, and the convected
    // heat was in no balance
    let text = format!("{convection}\n[[bc]]\ngroup = \"right\"\ntheta = 50.0\n");
    let case = write("h-and-theta", &text);
    let h = line_of(&text, "h = 2.5");
    let theta = text.lines().count() - 1; // the last [[bc]]'s group line
    fails_with(
        &tmc(&["check", case.to_str().unwrap()]),
        &[
            &format!("h-and-theta.toml:{h}"),
            "bc on \"right\": the group convects (`h`)",
            &format!("`theta` in the [[bc]] at line {theta}"),
        ],
    );
    // h = 0 insulates: it fixes no temperature (the heat source then has nowhere to go)
    let text = convection
        .replace("[[bc]]\ngroup = \"left\"\ntheta = 100.0\n", "")
        .replace("h = 2.5", "h = 0.0")
        .replacen("k = 5.0", "k = 5.0\nheat_source = 1.0", 1);
    let case = write("h-zero", &text);
    fails_with(
        &tmc(&["check", case.to_str().unwrap()]),
        &["h-zero.toml", "is not fixed", "convects (`h` > 0)"],
    );
    // a capacity without [time]: solved (stationary heat), with a note naming its line
    let transient = std::fs::read_to_string(root().join("cases/block-transient.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()));
    let (a, b) = (
        transient.find("[time]").unwrap(),
        transient.find("[[probe]]").unwrap(),
    );
    let text = format!("{}{}", &transient[..a], &transient[b..]);
    let case = write("capacity-without-time", &text);
    let report = checked(&case);
    let rho = line_of(&text, "rho_c = 400.0");
    assert!(
        report.contains(&format!(
            "note: line {rho}: region[0] (\"solid\"): `rho_c` has no effect: without [time]"
        )),
        "{report}"
    );
    // a mass density in a scene that does not deform: solved, with a note naming its line
    let conduction = std::fs::read_to_string(root().join("cases/slab-conduction.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()))
        .replace("k = 5.0\n", "k = 5.0\nrho = 7.8\n");
    let case = write("density-without-mechanics", &conduction);
    let report = checked(&case);
    let rho = line_of(&conduction, "rho = 7.8");
    assert!(
        report.contains(&format!(
            "note: line {rho}: region[0] (\"solid\"): `rho` has no effect: the scene does not deform"
        )),
        "{report}"
    );
    // a mass density on the solid alone beside friction in the medium: solved, with a note
    // naming the medium's friction line (the solids' mass alone does not pass slip events)
    let friction = std::fs::read_to_string(root().join("cases/friction-heating.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()))
        .replacen("kind = \"solid\"\n", "kind = \"solid\"\nrho = 1e-4\n", 1);
    let case = write("inertia-without-medium-mass", &friction);
    let report = checked(&case);
    let at = 1 + friction
        .lines()
        .position(|l| l.starts_with("friction = "))
        .unwrap();
    assert!(
        report.contains(&format!(
            "note: line {at}: region[1] (\"medium\") has friction but no `rho`"
        )),
        "{report}"
    );
    // the layer of friction-heating is four cells across its slip plane: a note, with the
    // region's friction line, that long slides drift below μ there; one cell across, none
    assert!(
        report.contains(&format!(
            "note: line {at}: region[1] (\"medium\"): its friction layer is 4 cells across its \
             slip plane"
        )),
        "{report}"
    );
    let one_across = friction.replace("l = 4 }", "l = 1 }");
    assert_ne!(one_across, friction);
    let one = checked(&write("friction-one-cell-across", &one_across));
    assert!(!one.contains("cells across its slip plane"), "{one}");
    assert!(one.contains("has friction but no `rho`"), "{one}");
    // a mass density small against the solid's stiffness over a step says nothing more; one
    // whose inertia outweighs it (a dynamic scene, where a quasi-static drag was meant) is a
    // note naming its line and the `rho` below which it would not
    assert!(!report.contains("inertia over a step"), "{report}");
    let heavy = friction.replacen("rho = 1e-4\n", "rho = 1e4\n", 1);
    let case = write("inertia-outweighs-stiffness", &heavy);
    let report = checked(&case);
    let at = line_of(&heavy, "rho = 1e4");
    assert!(
        report.contains(&format!(
            "note: line {at}: region[0] (\"solid\"): with `rho` = 1e4 its cells' inertia over a step"
        )) && report.contains("keep `rho` well below"),
        "{report}"
    );
    // a PETSc option without its dash (PETSc skipped it)
    let block = root().join("cases/block.toml");
    for (options, word) in [("ksp_type cg", "ksp_type"), ("-ksp_type cg gmres", "gmres")] {
        let o = tmc(&[
            "check",
            block.to_str().unwrap(),
            "--set",
            "solver.engine=\"petsc\"",
            "--set",
            &format!("solver.petsc.options=\"{options}\""),
        ]);
        fails_with(
            &o,
            &[&format!(
                "\"{word}\" is neither an option nor an option's value"
            )],
        );
    }
}

#[test]
fn under_time_a_failed_run_speaks_of_t_and_dt() {
    // a drag that cannot converge in 3 iterations: the steps shrink below the minimum; the
    // controller's steps are physical time steps, which the message called Δλ
    let dir = scratch("bad-time-words");
    let case = root().join("cases/friction-heating.toml");
    let sets = [
        "steps.max_iter=3",
        "mesh_options.params.n=4",
        "mesh_options.params.m=2",
        "mesh_options.params.l=1",
        "steps.min=1e-3",
    ];
    let mut args = vec!["solve", case.to_str().unwrap(), "-q", "-o"];
    let out = dir.join("out");
    args.push(out.to_str().unwrap());
    for s in &sets {
        args.extend(["--set", s]);
    }
    let e = fails_with(
        &tmc(&args),
        &[
            "load step from t = ",
            "(λ = 1.000000) failed with Δt = ",
            "below the minimum step",
        ],
    );
    assert!(!e.contains("Δλ"), "{e}");
    assert!(
        out.join("summary.json").exists(),
        "the steps that converged are kept"
    );
}

#[test]
fn a_study_setting_the_new_features_badly_ends_naming_the_variant_and_the_key() {
    // friction, [time] and convection keys set badly by a study's variant: the study file,
    // the variant and what is wrong named, no variant run, no folder made; what only the mesh
    // can tell (a normal of three components on a 2D mesh) fails that variant when it runs,
    // named at the end with its error, and the study exits 1
    let dir = scratch("bad-study-new-keys");
    let heating = root().join("cases/friction-heating.toml");
    let transient = root().join("cases/block-transient.toml");
    let tries = [
        (
            &heating,
            "\"region.medium.friction.mu\" = -1",
            "`friction.mu` must be finite and ≥ 0",
        ),
        (
            &heating,
            "\"region.medium.friction.heat_fraction\" = 2",
            "must be in [0, 1], got 2",
        ),
        (
            &heating,
            "\"region.medium.friction.c_f\" = 0",
            "`friction.c_f` must be positive",
        ),
        (&heating, "\"time.dt\" = -1", "`dt` must be positive"),
        (&heating, "\"time.end\" = 0", "`end`"),
        (
            &transient,
            "\"bc.solid_left.h\" = -5",
            "`h` must be finite and ≥ 0, got -5",
        ),
        (&transient, "\"region.solid.rho_c\" = -1", "rho_c"),
    ];
    // a study of `case` in `name`.toml: a fine variant, then one that sets `set`; run with -q
    let study = |name: &str, case: &Path, set: &str| {
        let study = dir.join(format!("{name}.toml"));
        std::fs::write(
            &study,
            format!(
                "case = \"{}\"\n[[variant]]\nname = \"fine\"\nset = {{ \"steps.tol\" = 1e-8 }}\n\
                 [[variant]]\nname = \"bad\"\nset = {{ {set} }}\n",
                case.display()
            ),
        )
        .unwrap();
        let out = dir.join(format!("out-{name}"));
        let args = [
            "study",
            study.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        (tmc(&args), out)
    };
    for (i, (case, set, says)) in tries.iter().enumerate() {
        let (o, out) = study(&format!("study{i}"), case, set);
        let e = fails_with(&o, &[&format!("study{i}.toml"), "variant \"bad\"", says]);
        assert!(!e.contains("panicked"), "{set}: {e}");
        assert!(!out.exists(), "{set}: nothing ran");
    }
    // known only with the mesh: the variant fails when it runs, the others run, the end of the
    // study names it (it said only "1 failed" with -q before)
    let normal = "\"region.medium.friction.normal\" = [0, 1, 0]";
    let (o, out) = study("mesh", &heating, normal);
    let e = fails_with(
        &o,
        &[
            "variant \"bad\" failed",
            "runs/bad/case.toml:",
            "`friction.normal` has 3 components; the mesh is 2D",
        ],
    );
    assert!(!e.contains("variant \"fine\""), "{e}");
    let table = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(
        table.contains("| fine |") && table.contains("failed: "),
        "{table}"
    );
}

/// The keys docs/CASE.md's tables list, each with the table it belongs in (its place in a
/// case: "" for the top level, "mesh_options", "region.solid", "region.medium", "friction",
/// "bc", "steps", "time", "solver", "solver.petsc", "output", "units", "probe") and whether
/// its type is a string or a bool (a number is the wrong type for it; a string for the rest),
/// and whether it is one number (for which −1e300 is out of range).
fn keys_of_the_case_reference() -> Vec<(&'static str, String, bool, bool)> {
    let doc = std::fs::read_to_string(root().join("docs/CASE.md")).unwrap();
    // each heading's tables, in order
    let places: &[(&str, &[&'static str])] = &[
        ("## Top level", &["", "mesh_options"]),
        ("## `[[region]]`: a solid", &["region.solid"]),
        (
            "## `[[region]]`: the third medium",
            &["region.medium", "friction"],
        ),
        ("## `[[bc]]`", &["bc"]),
        ("## `[steps]`", &["steps"]),
        ("## `[time]`", &["time"]),
        ("## `[solver]`", &["solver", "solver.petsc"]),
        ("## `[output]`", &["output", "units"]),
        ("## `[[probe]]`", &["probe"]),
    ];
    let (mut keys, mut tables, mut in_table) = (Vec::new(), None::<&[&str]>, false);
    let mut n = 0;
    for line in doc.lines() {
        if line.starts_with("## ") {
            tables = places
                .iter()
                .find(|(h, _)| line.starts_with(h))
                .map(|p| p.1);
            n = 0;
            in_table = false;
            continue;
        }
        let Some(t) = tables else { continue };
        if line.starts_with("| key |") {
            in_table = true;
            continue;
        }
        if !line.starts_with('|') {
            if in_table {
                n += 1;
            }
            in_table = false;
            continue;
        }
        if !line.starts_with("| `") || n >= t.len() {
            continue;
        }
        let cells: Vec<&str> = line.split('|').collect();
        let (names, kind) = (cells[1], cells.get(2).copied().unwrap_or(""));
        let textual = kind.contains("string") || kind.contains("bool") || kind.contains('"');
        // one number (a scalar): out of range is a value for it too
        let scalar = (kind.contains("number") || kind.contains("integer"))
            && !["numbers", "vector", "rows", "table", "point", ","]
                .iter()
                .any(|w| kind.contains(w));
        for name in names.split('`').skip(1).step_by(2) {
            keys.push((t[n], name.to_string(), textual, scalar));
        }
    }
    keys
}

#[test]
fn every_key_of_the_case_reference_of_the_wrong_type_is_refused_at_its_line_or_set() {
    let dir = scratch("bad-every-key");
    let mesh = root().join("geo/block.geo");
    let base = format!(
        "mesh = \"{}\"\n[mesh_options]\nparams = {{ n = 4, m = 4, l = 1 }}\n\
         [[region]]\ngroup = \"solid\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0\n\
         [[region]]\ngroup = \"medium\"\nkind = \"medium\"\ngamma = 1e-4\n\
         friction = {{ mu = 0.1, normal = [0, 1] }}\n\
         [[bc]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\n\
         [[bc]]\ngroup = \"top\"\nuy = -0.1\n\
         [steps]\nmax = 0.5\n[time]\nend = 1.0\ndt = 0.5\n[solver]\nlinear = \"auto\"\n\
         [solver.petsc]\nmethod = \"direct\"\n[output]\nevery = 1\n[units]\nlength = \"mm\"\n\
         [[probe]]\nname = \"p\"\nfield = \"ux\"\nat = [1.0, 1.0]\n",
        mesh.display()
    );
    let good = dir.join("base.toml");
    std::fs::write(&good, &base).unwrap();
    let o = tmc(&["check", good.to_str().unwrap()]);
    assert!(o.status.success(), "the base case is checked: {}", err(&o));
    let keys = keys_of_the_case_reference();
    assert!(
        keys.len() > 80,
        "{} keys read from docs/CASE.md",
        keys.len()
    );
    let mut wrong = Vec::new();
    // each table's first key through `tmc check` itself, the rest through the same check in
    // this process (the error and its causes as the command prints them, a panic caught): a
    // process costs a third of a second to start, and there are some 300 of them
    let mut through_cli = std::collections::HashSet::new();
    let check = |cli: bool, case: &Path, sets: &[(String, String)]| -> (bool, String) {
        if cli {
            let mut args = vec!["check".to_string(), case.display().to_string()];
            for (k, v) in sets {
                args.extend(["--set".to_string(), format!("{k}={v}")]);
            }
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = tmc(&args);
            return (o.status.success(), err(&o));
        }
        let opts = tmc::driver::SolveOptions {
            sets: sets.to_vec(),
            quiet: true,
            ..Default::default()
        };
        let checked = std::panic::catch_unwind(|| tmc::driver::check(case, &opts));
        match checked {
            Ok(Ok(_)) => (true, String::new()),
            Ok(Err(e)) => {
                let mut text = format!("error: {e}");
                let mut source = std::error::Error::source(&e);
                while let Some(s) = source {
                    text.push_str(&format!("\n  caused by: {s}"));
                    source = s.source();
                }
                (false, text)
            }
            Err(_) => (false, "panicked".into()),
        }
    };
    let values = |textual: bool, scalar: bool| match (textual, scalar) {
        (true, _) => vec!["1.5"],
        (false, true) => vec!["\"x\"", "-1e300"],
        (false, false) => vec!["\"x\""],
    };
    let cases = (keys.iter()).flat_map(|(place, key, textual, scalar)| {
        (values(*textual, *scalar).into_iter()).map(move |v| (*place, key, v))
    });
    for (place, key, value) in cases {
        // the line of the table the key goes in, and the line it is written on
        let header = match place {
            "" => None,
            "region.solid" => Some("kind = \"solid\"".to_string()),
            "region.medium" | "friction" => Some("kind = \"medium\"".to_string()),
            "bc" => Some("group = \"top\"".to_string()),
            "probe" => Some("name = \"p\"".to_string()),
            p => Some(format!("[{p}]")),
        };
        let mut lines: Vec<String> = base.lines().map(String::from).collect();
        let at = match (place, &header) {
            ("friction", _) => {
                let i = lines
                    .iter()
                    .position(|l| l.starts_with("friction"))
                    .unwrap();
                lines[i] = match key.as_str() {
                    "mu" => format!("friction = {{ mu = {value}, normal = [0, 1] }}"),
                    "normal" => format!("friction = {{ mu = 0.1, normal = {value} }}"),
                    _ => format!("friction = {{ mu = 0.1, normal = [0, 1], {key} = {value} }}"),
                };
                i
            }
            (_, header) => {
                let start = header
                    .as_ref()
                    .map_or(0, |h| lines.iter().position(|l| l == h).unwrap() + 1);
                let end = (start..lines.len())
                    .find(|&i| lines[i].starts_with('['))
                    .unwrap_or(lines.len());
                let line = format!("{key} = {value}");
                match (start..end).find(|&i| lines[i].starts_with(&format!("{key} = "))) {
                    Some(i) => {
                        lines[i] = line;
                        i
                    }
                    None => {
                        lines.insert(start, line);
                        start
                    }
                }
            }
        };
        let tag = if value == "-1e300" { "-range" } else { "" };
        let case = dir.join(format!("{}-{key}{tag}.toml", place.replace('.', "-")));
        std::fs::write(&case, lines.join("\n") + "\n").unwrap();
        let cli = through_cli.insert(place);
        let (passed, e) = check(cli, &case, &[]);
        let line = at + 1;
        let cited = e.contains(&format!(":{line}:")) || e.contains(&format!("line {line}"));
        if passed || !cited || e.contains("panicked") {
            wrong.push(format!("{place} {key} = {value} (line {line}): {e}"));
        }
        // the same from --set, on the case as the base has it
        let path = match place {
            "" => key.clone(),
            "region.solid" => format!("region.solid.{key}"),
            "region.medium" => format!("region.medium.{key}"),
            "friction" => format!("region.medium.friction.{key}"),
            "bc" => format!("bc.top.{key}"),
            "probe" => format!("probe.p.{key}"),
            p => format!("{p}.{key}"),
        };
        let set = format!("{path}={}", value.trim_matches('"'));
        let pair = [(path.clone(), value.trim_matches('"').to_string())];
        let (passed, e) = check(cli, &good, &pair);
        if passed || !e.contains(&format!("--set {set}")) || e.contains("panicked") {
            wrong.push(format!("--set {set}: {e}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} of {} keys:\n{}",
        wrong.len(),
        keys.len(),
        wrong.join("\n")
    );
}

/// Every region key of docs/CASE.md that belongs to one kind of region (solid or medium),
/// given well typed to a region of the other kind: refused by `check`, at the key's own line
/// from the file and naming the `--set` from the command line, saying what kind it belongs to.
#[test]
fn every_region_key_on_the_wrong_kind_is_refused_at_its_line_or_set() {
    let doc = std::fs::read_to_string(root().join("docs/CASE.md")).unwrap();
    // the first table after a heading: each key with its type column
    let table = |heading: &str| -> Vec<(String, String)> {
        let lines = doc.lines().skip_while(|l| !l.starts_with(heading));
        let rows = lines.skip_while(|l| !l.starts_with("| key |")).skip(2);
        rows.take_while(|l| l.starts_with('|'))
            .flat_map(|l| {
                let cells: Vec<&str> = l.split('|').map(str::trim).collect();
                let ty = cells[2].to_string();
                (cells[1]
                    .split(", ")
                    .map(|k| k.trim_matches('`').to_string()))
                .map(move |k| (k, ty.clone()))
                .collect::<Vec<_>>()
            })
            .collect()
    };
    let solid = table("## `[[region]]`: a solid");
    let medium = table("## `[[region]]`: the third medium");
    let only = |a: &[(String, String)], b: &[(String, String)]| -> Vec<(String, String)> {
        (a.iter())
            .filter(|(k, _)| k != "group" && k != "kind" && !b.iter().any(|(o, _)| o == k))
            .cloned()
            .collect()
    };
    // a value of the key's own type, so that what is refused is its place
    let value = |key: &str, ty: &str| -> String {
        if ty.contains("bool") {
            "true".into()
        } else if ty.contains("table") {
            "{ mu = 0.1, normal = [0, 1] }".into()
        } else if ty.contains("rows") {
            "[[0.5, 1.0], [1.0, 2.0]]".into()
        } else if ty.starts_with("`\"") {
            ty.split('`').nth(1).unwrap().to_string()
        } else if ty.contains("number") {
            "1.0".into()
        } else {
            panic!("no value for `{key}` of type \"{ty}\": teach this test one")
        }
    };
    let base = std::fs::read_to_string(root().join("cases/block.toml"))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/geo/", root().display()));
    let dir = scratch("bad-wrong-kind");
    let good = dir.join("base.toml");
    std::fs::write(&good, &base).unwrap();
    let (mut tried, mut wrong) = (0, Vec::new());
    // what is said after the region is named (its group is named as its kind here) names
    // the kind the key belongs to
    let names = |e: &str, kind: &str, belongs: &str| {
        e.split_once(&format!("(\"{kind}\"): "))
            .is_some_and(|(_, said)| said.contains(belongs))
    };
    for (keys, kind, belongs) in [
        (only(&solid, &medium), "medium", "solid"),
        (only(&medium, &solid), "solid", "medium"),
    ] {
        assert!(keys.len() >= 4, "{kind}: {keys:?}");
        for (key, ty) in keys {
            tried += 1;
            let v = value(&key, &ty);
            let mut lines: Vec<String> = base.lines().map(String::from).collect();
            let at = 1 + lines
                .iter()
                .position(|l| *l == format!("kind = \"{kind}\""))
                .unwrap();
            lines.insert(at, format!("{key} = {v}"));
            let case = dir.join(format!("{kind}-{key}.toml"));
            std::fs::write(&case, lines.join("\n") + "\n").unwrap();
            let o = tmc(&["check", case.to_str().unwrap()]);
            let e = err(&o);
            if o.status.success()
                || !e.contains(&format!(":{}:", at + 1))
                || !names(&e, kind, belongs)
            {
                wrong.push(format!("{key} = {v} on the {kind} (line {}): {e}", at + 1));
            }
            let set = format!("region.{kind}.{key}={v}");
            let o = tmc(&["check", good.to_str().unwrap(), "--set", &set]);
            let e = err(&o);
            if o.status.success()
                || !e.contains(&format!("--set {set}"))
                || !names(&e, kind, belongs)
            {
                wrong.push(format!("--set {set}: {e}"));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "{} of {tried}:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

#[test]
fn a_probe_named_as_a_column_tmc_writes_is_refused_at_its_name() {
    // history.csv would hold two columns of one name: a group's own columns (its reaction, its
    // F_t/F_n, its displacement) and the fixed ones, whether or not this scene writes them
    let dir = scratch("bad-probe-column");
    let probe = |name: &str| {
        format!("{SOLID}{HELD}[[probe]]\nname = \"{name}\"\nfield = \"ux\"\nat = [1.0, 0.5]\n")
    };
    let cases = vec![
        (
            "reaction",
            probe("R_right_x"),
            vec![
                "reaction-c.toml:",
                "probe name \"R_right_x\" is a column tmc writes for group \"right\"",
            ],
        ),
        (
            "displacement",
            probe("U_right_x"),
            vec!["probe name \"U_right_x\" is a column tmc writes for group \"right\""],
        ),
        (
            "ratio",
            probe("Ft_Fn_left"),
            vec!["probe name \"Ft_Fn_left\" is a column tmc writes for group \"left\""],
        ),
        (
            "fixed",
            probe("wall_seconds"),
            vec!["probe name \"wall_seconds\" is a column tmc writes in history.csv"],
        ),
    ];
    each_refused(&dir, cases);
    // a name that only looks like one is taken
    let p = slab_case(&dir, "taken", &probe("U_nowhere_x"));
    let o = tmc(&["check", p.to_str().unwrap()]);
    assert!(o.status.success(), "{}", err(&o));
}
