//! What a new user meets first: `ramp` per value and the message when an unramped value
//! breaks the first step, `tmc check`, `tmc solve --set`.

use crate::common;

use common::{
    case_body, point_array, root, scratch, shipped_case, solve_cli, solve_text, stderr, summary,
    tmc,
};
use std::path::{Path, PathBuf};

/// The block scene with its four `[[bc]]` blocks replaced by `bcs`.
fn block_with(bcs: &str) -> String {
    let body = case_body("block");
    let start = body.find("[[bc]]").unwrap();
    let end = body.find("[[probe]]").unwrap();
    format!("{}{bcs}\n{}", &body[..start], &body[end..])
}

const COARSE: &str = "n = 8, m = 4, l = 2";

/// `dir/NAME.toml`: the block's `.geo` as its mesh, then `body`.
fn block_case(dir: &Path, name: &str, body: &str) -> PathBuf {
    let case = dir.join(format!("{name}.toml"));
    let geo = root().join("geo/block.geo");
    std::fs::write(&case, format!("mesh = \"{}\"\n{body}", geo.display())).unwrap();
    case
}

#[test]
fn ramp_per_value_equals_separate_blocks_and_a_full_load_is_named() {
    // the block's own form: displacement ramped, temperatures held, in separate blocks
    let (separate, _) = solve_text("ramp-separate", "block.geo", COARSE, &case_body("block"));
    // one block per group, ramp per value
    let per_value = block_with(
        "[[bc]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\ntheta = 20.0\nramp = { theta = false }\n\
         [[bc]]\ngroup = \"top\"\nux = 0.0\nuy = -0.4\ntheta = 100.0\nramp = { theta = false, ux = true }\n",
    );
    let (joined, out) = solve_text("ramp-per-value", "block.geo", COARSE, &per_value);
    assert_eq!(joined.load_steps, separate.load_steps);
    assert_eq!(joined.newton_iterations, separate.newton_iterations);
    let (a, b) = (joined.probes["gap"], separate.probes["gap"]);
    assert!((a - b).abs() <= 1e-12 * b.abs(), "gap {a} vs {b}");
    // θ held at full value conducts from the start: step 0 is the equilibrium at λ = 0, its
    // heat in through the top equal to the heat out through the bottom, and the same at the end
    let (cols, rows) = common::history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (top, bottom) = (col("Q_top"), col("Q_bottom"));
    for row in [&rows[0], rows.last().unwrap()] {
        assert!(row[top] > 0.0, "Q_top {}", row[top]);
        assert!(
            (row[top] + row[bottom]).abs() < 1e-9 * row[top],
            "{} vs {}",
            row[top],
            row[bottom]
        );
    }
    assert!(rows[0][col("newton_iterations")] >= 1.0);

    // the whole block held: the displacement is applied at once; with two Newton iterations
    // allowed the first step cannot converge, and the message names the value applied in full
    let held = block_with(
        "[[bc]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\ntheta = 20.0\nramp = false\n\
         [[bc]]\ngroup = \"top\"\nux = 0.0\nuy = -0.4\ntheta = 100.0\nramp = false\n",
    );
    let dir = scratch("ramp-held");
    let case = block_case(
        &dir,
        "held",
        &format!(
            "[mesh_options]\nparams = {{ {COARSE} }}\n[steps]\nmin = 0.05\nmax_iter = 2\n{held}"
        ),
    );
    let o = solve_cli(&case, &dir.join("out"), &[]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(
        e.contains("applied in full from the first step") && e.contains("uy = -0.4 on \"top\""),
        "{e}"
    );
    // a ramp table naming a value the block does not give
    let bad = block_with("[[bc]]\ngroup = \"top\"\nuy = -0.4\nramp = { thetaa = false }\n");
    let case = block_case(&dir, "bad", &bad);
    let o = solve_cli(&case, &dir.join("out2"), &[]);
    let e = stderr(&o);
    assert!(
        !o.status.success()
            && e.contains("bad.toml:")
            && e.contains("names \"thetaa\"")
            && e.contains("it gives uy"),
        "{e}"
    );
}

/// `tmc check ARGS`, which must succeed: its report.
fn check_ok(args: &[&str]) -> String {
    let mut all = vec!["check"];
    all.extend_from_slice(args);
    let o = tmc(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn check_reports_what_a_solve_would_use_and_writes_nothing() {
    let out = check_ok(&[
        "cases/block.toml",
        "--set",
        "mesh_options.params={ n = 8, m = 4, l = 2 }",
    ]);
    for words in [
        "ready to solve",
        "group \"medium\" (2D): 16 elements",
        "group \"solid\" (2D): 32 elements",
        "group \"top\" (1D): 8 elements",
        "one-way coupled",
        "unknowns: ",
        // a one-way scene: two symmetric systems, each by faer's LDLᵀ
        "linear solver: mechanics: faer LDLᵀ in nested-dissection order; heat: faer LDLᵀ",
        "factor: ",
        "probes: gap",
    ] {
        assert!(out.contains(words), "\"{words}\" not in:\n{out}");
    }
    // the same numbers a solve reports
    let dir = scratch("check-vs-solve");
    let o = solve_cli(
        Path::new("cases/block.toml"),
        &dir.join("out"),
        &["--set", "mesh_options.params={ n = 8, m = 4, l = 2 }"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&dir.join("out"));
    let dofs = &s["dofs"];
    let line = format!(
        "unknowns: {} u, {} theta, {} p ({} free)",
        dofs["u"], dofs["theta"], dofs["p"], dofs["free"]
    );
    assert!(out.contains(&line), "\"{line}\" not in:\n{out}");
    // check writes nothing: no results folder, nothing beside the case
    let alone = scratch("check-alone");
    let case = block_case(&alone, "never-solved", &case_body("block"));
    let o = tmc(&["check", case.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!root().join("results/never-solved").exists());
    assert_eq!(std::fs::read_dir(&alone).unwrap().count(), 1);
    let o = tmc(&[
        "check",
        "cases/block.toml",
        "--set",
        "region.medium.gama=1e-5",
    ]);
    let e = stderr(&o);
    assert!(
        !o.status.success()
            && e.contains("with --set region.medium.gama=1e-5")
            && e.contains("unknown field `gama`"),
        "{e}"
    );
    // thermal expansion and the θ0 it is counted from, said per region
    let out = check_ok(&["cases/block.toml", "--set", "region.solid.alpha=1e-5"]);
    assert!(
        out.contains("thermal expansion in \"solid\": α = 0.00001 from θ0 = 0 (not given"),
        "{out}"
    );
    let out = check_ok(&[
        "cases/block.toml",
        "--set",
        "region.solid.alpha=1e-5",
        "--set",
        "region.solid.theta0=20.0",
    ]);
    assert!(
        out.contains("thermal expansion in \"solid\": α = 0.00001 from θ0 = 20\n"),
        "{out}"
    );
}

#[test]
fn check_estimates_a_3d_run_s_peak_memory_from_above() {
    // block-plate-3d-tm1 on 16×16 in plan (20 502 unknowns, faer's block-triangular GMRES
    // with single-precision factors), its first load step: the peak `tmc check` announces is
    // the peak the solve reports to within 5 % below and 25 % above (when each factor entry
    // counted as a double and an index, and the tangent as no more: 0.84 times the peak here,
    // 2.6 times at 1.1M)
    let sets = [
        "--set",
        "mesh_options.params={ n = 16, nb = 10, nm = 1, nq = 6 }",
        "--set",
        "steps.path=[0.0, 0.002]",
    ];
    let mut args = vec!["cases/block-plate-3d-tm1.toml"];
    args.extend_from_slice(&sets);
    let out = check_ok(&args);
    let estimate: f64 = out
        .split("entries; about ")
        .nth(1)
        .and_then(|r| r.split(" MB at the run's peak").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no estimate in:\n{out}"));
    let dir = scratch("check-memory");
    let o = solve_cli(
        Path::new("cases/block-plate-3d-tm1.toml"),
        &dir.join("out"),
        &sets,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let peak = summary(&dir.join("out"))["peak_memory_mb"]
        .as_f64()
        .unwrap();
    assert!(
        peak <= 1.05 * estimate && estimate <= 1.25 * peak,
        "estimated {estimate} MB, peak {peak} MB"
    );
}

#[test]
fn solve_set_equals_the_edited_case() {
    // --set on the command line and the same keys written into the case give the same run
    let (edited, _) = solve_text(
        "set-edited",
        "block.geo",
        COARSE,
        &case_body("block").replace("gamma = 1e-4", "gamma = 2e-4"),
    );
    let dir = scratch("set-cli");
    let case = block_case(&dir, "block", &case_body("block"));
    let o = solve_cli(
        &case,
        &dir.join("out"),
        &[
            "--set",
            "mesh_options.params={ n = 8, m = 4, l = 2 }",
            "--set",
            "region.medium.gamma=2e-4",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&dir.join("out"));
    assert_eq!(
        s["load_steps"].as_u64().unwrap() as usize,
        edited.load_steps
    );
    let gap = s["probes"]["gap"].as_f64().unwrap();
    assert!(
        (gap - edited.probes["gap"]).abs() <= 1e-12 * gap.abs(),
        "{gap} vs {}",
        edited.probes["gap"]
    );
}

#[test]
fn a_study_without_measure_or_reference_tabulates() {
    let dir = scratch("study-table");
    let study = dir.join("sweep.toml");
    std::fs::write(
        &study,
        format!(
            "case = \"{}\"\nshow = [\"gap\"]\n\
             [[variant]]\nname = \"g4\"\nset = {{ \"mesh_options.params\" = {{ n = 4, m = 2, l = 1 }}, \"region.medium.gamma\" = 1e-4 }}\n\
             [[variant]]\nname = \"g3\"\nset = {{ \"mesh_options.params\" = {{ n = 4, m = 2, l = 1 }}, \"region.medium.gamma\" = 1e-3 }}\n",
            root().join("cases/block.toml").display()
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = tmc(&[
        "study",
        study.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = csv::Reader::from_path(out.join("study.csv")).unwrap();
    let head = r.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 2);
    let gap = head.iter().position(|c| c == "gap").unwrap();
    let (g4, g3): (f64, f64) = (rows[0][gap].parse().unwrap(), rows[1][gap].parse().unwrap());
    assert!(
        g4 > 0.0 && g3 > g4,
        "a stiffer medium keeps a wider gap: {g4} {g3}"
    );
    assert!(!out.join("error_vs_time.png").exists());
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(md.contains("it tabulates"), "{md}");
}

#[test]
fn a_body_no_boundary_group_touches_is_reported() {
    // the README's cylinder on a plate without the cylinder's "rim": nothing can hold the
    // cylinder but the medium
    let dir = scratch("untouched-body");
    let geo = dir.join("norim.geo");
    let text = std::fs::read_to_string(root().join("geo/cylinder-plate.geo")).unwrap();
    let without: String = text
        .lines()
        .filter(|l| !l.contains("\"rim\""))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(without, text, "the .geo has a rim group to leave out");
    std::fs::write(&geo, without).unwrap();
    let o = tmc(&["mesh", geo.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("warning: group \"cylinder\"")
            && e.contains("touches no boundary group")
            && e.contains("only \"medium\" holds it"),
        "{e}"
    );
    // the medium between the two bodies is not a body to hold
    assert!(!e.contains("group \"medium\""), "{e}");
    // with the rim, no such warning
    let o = tmc(&[
        "mesh",
        "geo/cylinder-plate.geo",
        "-o",
        dir.join("rim.msh").to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(
        o.status.success() && !e.contains("touches no boundary group"),
        "{e}"
    );
}

#[test]
fn a_solid_only_the_medium_holds_is_reported() {
    let dir = scratch("medium-alone");
    let text = shipped_case("cylinder-plate");
    let check = |name: &str, text: &str| {
        let case = dir.join(name);
        std::fs::write(&case, text).unwrap();
        check_ok(&[case.to_str().unwrap()])
    };
    let pushed = "ux = 0.0\nuy = -0.15\n";
    assert!(text.contains(pushed), "the case pushes the cylinder's rim");
    // pressed down at its rim but free to slide: the usual slip, a warning
    let out = check("slides.toml", &text.replace(pushed, "uy = -0.15\n"));
    assert!(
        out.contains("warning: the solid body of \"cylinder\"")
            && out.contains("held in part: it can move freely in x but for the third medium"),
        "{out}"
    );
    // heated at its rim, not pushed: floating in the medium, a note
    let out = check("floats.toml", &text.replace(pushed, ""));
    assert!(
        out.contains("note: the solid body of \"cylinder\"")
            && out.contains("has no prescribed displacement")
            && !out.contains("warning")
            && !out.contains("of \"plate\""),
        "{out}"
    );
    // held in full, as shipped: neither
    let out = check("held.toml", &text);
    assert!(!out.contains("warning") && !out.contains("note"), "{out}");
    // with the medium made again, a remake takes what holds it: a warning, either way
    let medium = "kind = \"medium\"\n";
    assert_eq!(text.matches(medium).count(), 1);
    let remade = text.replace(medium, &format!("{medium}remake = true\n"));
    let out = check("floats-remade.toml", &remade.replace(pushed, ""));
    assert!(
        out.contains("warning: the solid body of \"cylinder\"")
            && out.contains("alone holds it, and the medium is made again (`remake`)")
            && !out.contains("note"),
        "{out}"
    );
    let out = check(
        "slides-remade.toml",
        &remade.replace(pushed, "uy = -0.15\n"),
    );
    assert!(
        out.contains("it can move freely in x but for the third medium")
            && out.contains("(the medium is made again (`remake`): each remake sets"),
        "{out}"
    );
    let out = check("held-remade.toml", &remade);
    assert!(!out.contains("warning") && !out.contains("note"), "{out}");
}

#[test]
fn a_surface_in_no_group_is_reported() {
    let dir = scratch("forgotten-group");
    let geo = dir.join("forgot.geo");
    let two = "Point(1)={0,0,0};Point(2)={1,0,0};Point(3)={1,1,0};Point(4)={0,1,0};\
               Point(5)={1,2,0};Point(6)={0,2,0};\n\
               Line(1)={1,2};Line(2)={2,3};Line(3)={3,4};Line(4)={4,1};Line(5)={3,5};\
               Line(6)={5,6};Line(7)={6,4};\n\
               Curve Loop(1)={1,2,3,4};Plane Surface(1)={1};\
               Curve Loop(2)={-3,5,6,7};Plane Surface(2)={2};\n\
               Physical Surface(\"solid\")={2};\n";
    // only the upper surface is tagged: the lower one's cells are dropped, with a warning
    std::fs::write(&geo, format!("{two}Physical Curve(\"top\")={{6}};\n")).unwrap();
    let o = tmc(&["mesh", geo.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("surfaces 1 belong to no physical group") && e.contains("without contact"),
        "{e}"
    );
    // a boundary group on the dropped surface: the error says why
    std::fs::write(&geo, format!("{two}Physical Curve(\"bottom\")={{1}};\n")).unwrap();
    let o = tmc(&["mesh", geo.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(
        !o.status.success()
            && e.contains("\"bottom\" has a node")
            && e.contains("surfaces 1 belong to no physical group"),
        "{e}"
    );
}

#[test]
fn a_log_gets_one_line_per_step_and_history_the_wall_time() {
    let dir = scratch("log-lines");
    let out = dir.join("out");
    // stderr is a pipe here, as in a log file: no progress bar, a line per step
    let o = tmc(&[
        "solve",
        "cases/block-transient.toml",
        "-o",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let s = summary(&out);
    let steps = s["load_steps"].as_u64().unwrap() as usize;
    let lines: Vec<&str> = e.lines().filter(|l| l.starts_with("step ")).collect();
    assert_eq!(lines.len(), steps, "{e}");
    // physical time first under [time]
    assert!(
        lines[0].contains("t 1.0000e-1") && lines[0].contains(" s"),
        "{}",
        lines[0]
    );
    let (cols, rows) = common::history(&out);
    assert_eq!(cols.last().map(String::as_str), Some("wall_seconds"));
    let w: Vec<f64> = rows.iter().map(|r| *r.last().unwrap()).collect();
    assert!(w.windows(2).all(|p| p[1] >= p[0]) && w[0] >= 0.0, "{w:?}");
    assert!(*w.last().unwrap() <= s["wall_seconds"].as_f64().unwrap());
    // -q: nothing per step
    let o = solve_cli(Path::new("cases/block-transient.toml"), &out, &[]);
    assert!(!stderr(&o).contains("step "), "{}", stderr(&o));
}

#[test]
fn output_every_n_steps_keeps_the_first_and_the_last() {
    let dir = scratch("output-every");
    let out = dir.join("out");
    let o = solve_cli(
        Path::new("cases/block-transient.toml"),
        &out,
        &["--set", "output.every=3"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, rows) = common::history(&out);
    let steps = rows.len() - 1;
    assert!(
        steps % 3 != 0,
        "the scene's step count shows the last step's own file"
    );
    let mut want: Vec<usize> = (0..=steps).filter(|k| k % 3 == 0).collect();
    want.push(steps);
    let mut have: Vec<usize> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            n.strip_prefix("step_")?.strip_suffix(".vtu")?.parse().ok()
        })
        .collect();
    have.sort();
    assert_eq!(have, want);
    let pvd = std::fs::read_to_string(out.join("block-transient.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), want.len());
    let o = tmc(&[
        "check",
        "cases/block-transient.toml",
        "--set",
        "output.every=0",
    ]);
    assert!(
        stderr(&o).contains("`every` must be at least 1"),
        "{}",
        stderr(&o)
    );
}

/// Every file, function and type the recipes of docs/ARCHITECTURE.md name exists: a
/// renamed registration point fails here instead of leaving a recipe that misleads.
#[test]
fn the_architecture_recipes_name_what_exists() {
    let doc = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).unwrap();
    let recipes = doc
        .split("## Recipes")
        .nth(1)
        .and_then(|r| r.split("\n## ").next())
        .expect("a Recipes section");
    let sources: String = (common::source_files().iter())
        .map(|f| std::fs::read_to_string(root().join("src").join(f)).unwrap())
        .collect();
    let (mut files, mut names) = (0, 0);
    for token in recipes.split('`').skip(1).step_by(2) {
        if token.contains('<') || token.contains(' ') {
            continue; // a template (`material/<name>.rs`) or a phrase
        }
        if token.ends_with(".rs") || token.ends_with(".py") || token.ends_with('/') {
            let found = ["", "src/", "tests/", "validation/fenicsx/"]
                .iter()
                .any(|d| root().join(format!("{d}{token}")).exists());
            assert!(
                found,
                "ARCHITECTURE.md's recipes name `{token}`, which is not there"
            );
            files += 1;
        } else if token.chars().next().is_some_and(|c| c.is_ascii_uppercase())
            || token.contains('_')
            || token.contains("::")
        {
            // a type, function or method: its last segment is defined somewhere in src/
            let name = token.trim_end_matches("()").trim_end_matches('!');
            let name = name.rsplit("::").next().unwrap();
            let defined = [
                format!("fn {name}"),
                format!("struct {name}"),
                format!("enum {name}"),
                format!("trait {name}"),
                format!("    {name}("),
                format!("    {name} {{"),
                format!("macro_rules! {name}"),
            ]
            .iter()
            .any(|d| sources.contains(d.as_str()));
            assert!(
                defined,
                "ARCHITECTURE.md's recipes name `{token}`, defined nowhere in src/"
            );
            names += 1;
        }
    }
    assert!(
        files > 10 && names > 10,
        "{files} files, {names} names read"
    );
}

#[test]
fn the_readme_geometry_is_the_shipped_one_and_it_solves() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for f in ["geo/cylinder-plate.geo", "cases/cylinder-plate.toml"] {
        let text = std::fs::read_to_string(root().join(f)).unwrap();
        assert!(readme.contains(&text), "the README shows {f} as it is");
    }
    let dir = scratch("cylinder-plate");
    let out = dir.join("out");
    let o = solve_cli(Path::new("cases/cylinder-plate.toml"), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    // the gap of 0.1 closes to the medium's thin remnant under a push of 0.15
    let gap = s["probes"]["gap"].as_f64().unwrap();
    assert!(gap > 0.0 && gap < 0.02, "gap {gap}");
    // equilibrium and the heat balance of the two held groups
    let r = &s["reactions"];
    let (fb, fr) = (
        r["bottom"]["y"].as_f64().unwrap(),
        r["rim"]["y"].as_f64().unwrap(),
    );
    assert!(fb > 0.0 && (fb + fr).abs() <= 1e-9 * fb, "forces {fb} {fr}");
    let (qb, qr) = (
        r["bottom"]["heat"].as_f64().unwrap(),
        r["rim"]["heat"].as_f64().unwrap(),
    );
    assert!(qr > 0.0 && (qb + qr).abs() <= 1e-9 * qr, "heat {qb} {qr}");
    // no sideways drift of the symmetric scene
    assert!(r["bottom"]["x"].as_f64().unwrap().abs() < 1e-3 * fb);
}

#[test]
fn restart_continues_an_interrupted_run_exactly() {
    // the transient block: physical time, history variables (θ of the last step), growing
    // steps; stopped by Ctrl-C after a few steps, then continued with --restart
    let dir = scratch("restart");
    let (full, stopped) = (dir.join("full"), dir.join("stopped"));
    let case = root().join("cases/block-transient.toml");
    let o = solve_cli(&case, &full, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = common::solve_interrupted(&case, &stopped);
    assert!(!o.status.success(), "the run was interrupted");
    let all_rows = common::history(&full).1;
    let done = common::history(&stopped).1.len();
    assert!(
        done >= 3 && done < all_rows.len(),
        "stopped after {done} of {} rows",
        all_rows.len()
    );

    // a changed case is refused (only [steps] controls and [output] may change), nothing lost
    let o = solve_cli(
        &case,
        &stopped,
        &["--restart", "--set", "region.solid.k=11.0"],
    );
    assert!(
        !o.status.success()
            && stderr(&o).contains("has changed since: region[0].k: 100.0 then, 11.0 now"),
        "{}",
        stderr(&o)
    );
    assert_eq!(common::history(&stopped).1.len(), done);
    // no checkpoint: said so
    let o = solve_cli(&case, &dir.join("nothing"), &["--restart"]);
    assert!(
        !o.status.success() && stderr(&o).contains("cannot restart"),
        "{}",
        stderr(&o)
    );

    let (cols, before) = common::history(&stopped);
    let wall = cols.iter().position(|c| c == "wall_seconds").unwrap();
    let o = solve_cli(&case, &stopped, &["--restart", "--set", "steps.min=1e-6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // the same rows, every column but the wall time, to the last bit
    common::same_history_to_the_bit(&full, &stopped);
    // the wall seconds go on from the stopped run's: never back, and at the end no fewer
    // than the assembly's and the solver's, which count both parts
    let rows = common::history(&stopped).1;
    assert!(rows.windows(2).all(|w| w[1][wall] >= w[0][wall]));
    assert!(rows[done][wall] >= before[done - 1][wall]);
    let s = common::summary(&stopped);
    let seconds = |key: &str| s[key].as_f64().unwrap();
    assert!(
        seconds("wall_seconds") >= seconds("assembly_seconds") + seconds("solver_seconds"),
        "{s}"
    );
    let (a, b) = (common::summary(&full), common::summary(&stopped));
    for key in [
        "converged",
        "load_steps",
        "rejected_steps",
        "newton_iterations",
        "linear_solves",
        "probes",
        "reactions",
        "heat_stored",
        "heat_in",
        "external_work",
        "energy",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
    let last = format!("step_{:04}.vtu", all_rows.len() - 1);
    for field in ["u", "theta", "von_mises"] {
        let (x, y) = (
            point_array(&full.join(&last), field),
            point_array(&stopped.join(&last), field),
        );
        assert!(
            x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{field}"
        );
    }
}

#[test]
fn units_named_in_the_case_label_the_plot_axes() {
    let dir = scratch("units");
    let out = dir.join("out");
    let units = [
        "units.length=mm",
        "units.force=N",
        "units.time=s",
        "units.temperature=K",
    ];
    let sets: Vec<&str> = units.iter().flat_map(|u| ["--set", *u]).collect();
    let o = solve_cli(Path::new("cases/block-transient.toml"), &out, &sets);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    // energy and power made from those named
    assert_eq!(s["units"]["energy"], "N·mm");
    assert_eq!(s["units"]["power"], "N·mm/s");
    let q = &s["quantities"];
    for (column, quantity) in [
        ("gap", "length"),
        ("theta_block", "temperature"),
        ("R_top_y", "force"),
        ("Q_bottom", "power"),
        ("energy", "energy"),
        ("heat_in", "energy"),
        ("time", "time"),
    ] {
        assert_eq!(q[column], quantity, "{column}");
    }
    for counted in ["lambda", "newton_iterations", "min_J_solid", "wall_seconds"] {
        assert!(q.get(counted).is_none(), "{counted}");
    }
    let labels = tmc::plot::Labels::read(&out);
    assert_eq!(labels.axis("gap"), "gap [mm]");
    assert_eq!(labels.axis("Q_bottom"), "Q_bottom [N·mm/s]");
    assert_eq!(labels.axis("heat_in"), "heat supplied [N·mm]");
    assert_eq!(labels.axis("time"), "time t [s]");
    assert_eq!(labels.axis("lambda"), "load factor λ");
    assert_eq!(labels.default_x(), "time");
    // drawn: every default column but the wall clock, 900 × 600
    let o = tmc(&["plot", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let png = std::fs::read(out.join("Q_bottom.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let size = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
    assert_eq!((size(16), size(20)), (900, 600));
    assert!(!out.join("wall_seconds.png").exists());

    // without [units] the axes name the quantity, and a steady run is drawn against λ
    let plain = dir.join("plain");
    let o = solve_cli(Path::new("cases/block.toml"), &plain, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let labels = tmc::plot::Labels::read(&plain);
    assert_eq!(labels.axis("gap"), "gap [length]");
    assert_eq!(labels.axis("Q_top"), "Q_top [power]");
    assert_eq!(labels.axis("time"), "time t");
    assert_eq!(labels.default_x(), "lambda");
    assert!(summary(&plain)["units"].as_object().unwrap().is_empty());
}
