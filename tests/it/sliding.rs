//! Bodies sliding through a medium made again as they move (`remake` of a medium region):
//! the README's cylinder slid along its plate keeps the normal force of its press and meets
//! no drag on average, where the Lagrangian medium ploughs, and swings no more than the same
//! mesh does in exact contact; and what `remake` cannot do yet is refused by `tmc check` and
//! `tmc solve` alike.

use crate::common;
use common::*;
use std::path::Path;

/// Over the slide (t > 1) of a run in `dir`: the normal force at the end of the press, the
/// smallest and largest normal force, the time-weighted mean of F_t/F_n and its largest size,
/// F_t and F_n being the reactions of the cylinder's rim.
fn slide_forces(dir: &Path) -> (f64, f64, f64, f64, f64) {
    let (cols, rows) = history(dir);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, fx, fy, probe) = (col("time"), col("R_rim_x"), col("R_rim_y"), col("Ft_Fn"));
    let press = rows.iter().find(|r| r[t] == 1.0).expect("the press's end");
    let fn0 = -press[fy];
    let slide: Vec<&Vec<f64>> = rows.iter().filter(|r| r[t] >= 1.0).collect();
    let normal: Vec<f64> = slide.iter().map(|r| -r[fy]).collect();
    let ratio: Vec<f64> = slide.iter().map(|r| r[fx] / -r[fy]).collect();
    // the case's force-ratio probe is that ratio, and so is the rim's own column: split
    // along the normal of the plate's face, [0, 1], where the contact presses
    let own = col("Ft_Fn_rim");
    for (r, ratio) in slide.iter().zip(&ratio) {
        assert!((r[probe] - ratio).abs() < 1e-12, "{} vs {ratio}", r[probe]);
        assert!((r[own] - ratio).abs() < 1e-12, "{} vs {ratio}", r[own]);
    }
    let span = slide.last().unwrap()[t] - 1.0;
    let mean = (1..slide.len())
        .map(|i| (slide[i][t] - slide[i - 1][t]) * ratio[i])
        .sum::<f64>()
        / span;
    let lo = normal.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = normal.iter().copied().fold(0.0, f64::max);
    let most = ratio.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    (fn0, lo, hi, mean, most)
}

/// The case `body` solved on the README's mesh (h = 0.1) in a scratch folder named `name`:
/// its output folder and summary.
fn solved_on_readme_mesh(name: &str, body: &str) -> (std::path::PathBuf, serde_json::Value) {
    let case = case_file(name, "cylinder-plate.geo", "params = { h = 0.1 }", body);
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    (out, s)
}

/// The case `body`, its medium made again settled after each remake (`settle`).
fn settled(body: &str) -> String {
    assert_eq!(body.matches("remake = true\n").count(), 1, "{body}");
    body.replace("remake = true\n", "remake = true\nsettle = true\n")
}

/// The README's cylinder slid as `cases/cylinder-slide.toml` slides it, its mechanics settled
/// after each remake (`settle`): what a remake changes is measured, and the forces over the
/// slide are those of the run in `out`, whose next step started from the state as carried
/// (`forces`, as [`slide_forces`] reads them).
fn settled_alike(out: &Path, forces: (f64, f64, f64, f64, f64)) {
    let body = settled(&case_body("cylinder-slide"));
    let (settled, s) = solved_on_readme_mesh("cylinder-slide-settled", &body);
    // what a remake changes of the rim's reaction at the settled state (measured: 1.3 % at
    // most, 1.0 % when made again before each pass too; 2.3 % when each new cell of the
    // closed layer carried the old J where it stood); the scene conducts no heat
    let force = s["medium_remade_force_change"].as_f64().unwrap();
    assert!(force > 0.0 && force < 0.02, "a remake changed F by {force}");
    assert_eq!(s["medium_remade_heat_change"], 0.0);
    // each remake's settling converged
    assert_eq!(s["medium_remade_unsettled"], 0);
    // measured: F_n the same to 1.2e-6 of the press's, the largest F_t/F_n to 2e-6 and its
    // mean to 8e-5, where the settlings took 37 Newton iterations of the run's 408
    let (fn0, lo, hi, mean, most) = slide_forces(&settled);
    let (lo, hi) = (lo / fn0, hi / fn0);
    let (fn1, lo1, hi1, mean1, most1) = forces;
    assert!((fn0 - fn1).abs() < 1e-12 * fn0, "pressed {fn0} and {fn1}");
    assert!(
        (lo - lo1 / fn1).abs() < 1e-4 && (hi - hi1 / fn1).abs() < 1e-4,
        "F_n / the press's: {lo} to {hi} settled, {} to {} not",
        lo1 / fn1,
        hi1 / fn1
    );
    assert!(
        (most - most1).abs() < 1e-4 && (mean - mean1).abs() < 5e-4,
        "F_t/F_n {mean} on average, {most} at most settled; {mean1}, {most1} not"
    );
    let its = |s: &serde_json::Value| s["newton_iterations"].as_u64().unwrap();
    assert!(its(&summary(out)) < its(&s), "the settlings' iterations");
}

#[test]
fn the_cylinder_slides_on_a_medium_made_again_with_the_force_of_its_press_and_no_drag() {
    let ran = std::time::Instant::now();
    let (made, out) = solve_case("cylinder-slide");
    let ran = ran.elapsed().as_secs_f64();
    // a node's pass over the end of a face is made again once, after it, where the medium is
    // fresh, and once for nodes that pass within a twentieth of an edge of each other
    // (measured: 13 remakes; 19 one per pass; 40 when each was made again before it and after)
    assert!(
        (1..=30).contains(&made.medium_remade),
        "made again {} times",
        made.medium_remade
    );
    // the next step starts from the state as carried: what a remake changes is not measured
    let remade = summary(&out);
    for key in ["force", "heat"] {
        assert!(remade[format!("medium_remade_{key}_change")].is_null());
    }
    assert!(remade["medium_remade_unsettled"].is_null());
    // the remakes' own time is a part of the run's
    let seconds = remade["medium_remade_seconds"].as_f64().unwrap();
    let wall = remade["wall_seconds"].as_f64().unwrap();
    assert!(seconds > 0.0 && seconds < wall, "{seconds} s of {wall} s");
    // and the run's seconds are those it ran, each remake's counted once (the run goes on
    // from a checkpoint after each: counted from the run's start and again from the
    // checkpoint's seconds, the square pad in 3D, made again 225 times, 168 s for a run of 84)
    assert!(wall <= ran, "wall_seconds {wall} for a run of {ran} s");
    let (fn0, lo, hi, mean, most) = slide_forces(&out);
    settled_alike(&out, (fn0, lo, hi, mean, most));
    // measured: F_n 1.209 to 1.325 against 1.325 at the press's end; F_t/F_n −0.007 on
    // average, 0.105 at most (it swings as the cylinder's facets pass the plate's nodes;
    // −0.003 and 0.097 when made again before each pass too; 0.100 on gmsh's triangles).
    // The penalty per reference volume held the slide: 0.45 on average, 1.2 at most
    assert!(
        lo > 0.88 * fn0 && hi < 1.05 * fn0,
        "F_n {lo} to {hi}, {fn0} pressed"
    );
    assert!(mean.abs() < 0.01, "F_t/F_n {mean} on average");
    assert!(most < 0.15, "F_t/F_n {most} at most");
    // drawn against the pseudo-time (λ holds at 1 through the slide), the ratio by its name
    let h = tmc::plot::History::read(&out.join("history.csv")).unwrap();
    assert_eq!(tmc::plot::Labels::read(&out).default_x_of(&h), "time");
    let o = tmc(&["plot", out.to_str().unwrap(), "-c", "Ft_Fn"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("Ft_Fn.png").exists());
    // and against the slide: the rim's displacements are columns, along the bc's paths
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, ux, uy) = (col("time"), col("U_rim_x"), col("U_rim_y"));
    for r in &rows {
        let (press, slide) = (r[t].min(1.0), (r[t] - 1.0).max(0.0));
        assert!((r[uy] + 0.15 * press).abs() < 1e-12, "{r:?}");
        assert!((r[ux] - 0.3 * slide).abs() < 1e-12, "{r:?}");
    }
    let o = tmc(&[
        "plot",
        out.to_str().unwrap(),
        "-x",
        "U_rim_x",
        "-c",
        "Ft_Fn_rim",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("Ft_Fn_rim.png").exists());
    assert!(summary(&out)["probes"]["Ft_Fn"].as_f64().is_some());
    // the Lagrangian medium on the same slide ploughs (measured: F_n to 1.79 times the
    // press's, F_t/F_n 0.128 on average)
    let lagrangian = case_file(
        "cylinder-slide-lagrangian",
        "cylinder-plate.geo",
        "params = { h = 0.1 }",
        &case_body("cylinder-slide").replace("remake = true\n", ""),
    );
    let out = lagrangian.with_file_name("out");
    let o = solve_cli(&lagrangian, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(summary(&out)["medium_remade"], 0);
    assert!(summary(&out)["medium_remade_seconds"].is_null());
    assert!(summary(&out)["medium_remade_unsettled"].is_null());
    let (fn0, _, hi, mean, _) = slide_forces(&out);
    assert!(hi > 1.5 * fn0, "ploughed: F_n {hi}, {fn0} pressed");
    assert!(mean > 0.1, "ploughed: F_t/F_n {mean} on average");
}

/// The README's cylinder, as its mesh has it (a rigid polygon of the rim's nodes, or the circle
/// they were drawn on: `obstacle`), slid 0.3 over the plate cells of the mesh in `msh` in
/// exact contact, without friction and without a medium (`validation/cylinder-exact/`,
/// FEniCSx): the normal force at the press's end, the least and the largest normal force over
/// the slide as shares of it, and the largest |F_t/F_n|.
fn in_exact_contact(msh: &Path, obstacle: &str) -> (f64, f64, f64, f64) {
    let o = std::process::Command::new("/usr/bin/python3")
        .arg(root().join("validation/cylinder-exact/cylinder.py"))
        .arg(msh)
        .args(["--obstacle", obstacle, "--slide", "0.3", "--steps", "120"])
        .output()
        .expect("/usr/bin/python3 runs (make deps installs python3-dolfinx, python3-gmsh)");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}\n{}", stderr(&o));
    let pressed: f64 = (text.lines())
        .find_map(|l| l.strip_prefix("# pressed 0.15: F_n "))
        .expect("the press's force")
        .parse()
        .unwrap();
    let rows: Vec<Vec<f64>> = (text.lines())
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 120, "{text}");
    let normal = rows.iter().map(|r| r[2] / pressed);
    let lo = normal.clone().fold(f64::INFINITY, f64::min);
    let hi = normal.fold(0.0, f64::max);
    let most = rows.iter().fold(0.0f64, |m, r| m.max(r[3].abs()));
    (pressed, lo, hi, most)
}

/// What swings as the README's cylinder slides is its mesh's, not the medium's: the same
/// polygon slid over the same plate cells in exact contact, with no medium, swings more, and
/// presses as hard. Item 3 of issue 68 asks |F_t/F_n| <= 0.02 there; exact contact meets it
/// only with a round cylinder.
#[test]
fn the_cylinder_swings_no_more_than_the_same_mesh_in_exact_contact() {
    let (_, out) = solve_case("cylinder-slide");
    let (fn0, lo, hi, _, most) = slide_forces(&out);
    let (lo, hi) = (lo / fn0, hi / fn0);
    let msh = out.join("mesh.msh");
    // measured (penalty 1e4 G/h, 20 points an edge): the polygon 1.317 pressed, F_n 0.907 to
    // 1.000 of it, 0.120 at most; the circle 1.335 pressed, 0.019 at most
    let (pressed, lo_exact, hi_exact, most_exact) = in_exact_contact(&msh, "polygon");
    let (_, _, _, most_round) = in_exact_contact(&msh, "circle");
    assert!(
        most_exact > 0.1,
        "exact contact of the polygon: {most_exact} at most"
    );
    assert!(
        most_round < 0.025,
        "exact contact of the circle: {most_round} at most"
    );
    // measured: tmc 1.325 pressed, F_n 0.913 to 1.000 of it, F_t/F_n 0.1045 at most
    assert!(
        (fn0 - pressed).abs() < 0.02 * pressed,
        "pressed: F_n {fn0}, {pressed} in exact contact"
    );
    assert!(
        lo > lo_exact - 0.02 && hi < hi_exact + 0.02,
        "F_n {lo} to {hi} of the press's, {lo_exact} to {hi_exact} in exact contact"
    );
    assert!(
        most <= most_exact,
        "F_t/F_n {most} at most, {most_exact} in exact contact"
    );
}

/// The slide of 0.5 (to 0.1 of the medium's right face), on the README's mesh and on
/// one twice as fine: it completes, the normal force stays that of the press, and what swings
/// is the facets passing each other, less on the finer mesh. As it stood before each remade
/// layer had one thickness of reference, h = 0.1 stalled at a slide of 0.39 and h = 0.05 at
/// 0.12.
/// `cases/cylinder-slide.toml` slid 0.5 instead of 0.3, its mesh's `[mesh_options]` line
/// `params`, solved in the scratch folder `name`: the run reaches the slide's end (t = 2).
/// Its output folder (a `.vtu` of the first and the last state only). `settle`: the
/// mechanics settled after each remake, what it changed measured.
fn slid_half(name: &str, params: &str, settle: bool) -> std::path::PathBuf {
    let body = case_body("cylinder-slide").replace("ux = 0.3\n", "ux = 0.5\n");
    assert!(body.contains("ux = 0.5"));
    let body = if settle { settled(&body) } else { body };
    let body = body + common::ENDS_ONLY;
    let case = case_file(name, "cylinder-plate.geo", params, &body);
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{params}: {}", stderr(&o));
    let (cols, rows) = history(&out);
    let t = cols.iter().position(|c| c == "time").unwrap();
    let end = rows.last().unwrap()[t];
    assert!((end - 2.0).abs() < 1e-9, "{params}: slid to t = {end}");
    out
}

#[test]
fn the_cylinder_slides_its_whole_way_on_two_meshes() {
    // (h, F_n's band about the press's, largest |F_t/F_n|); measured: h = 0.1 F_n 0.900 to
    // 1.000 of the press's, F_t/F_n 0.113 at most (0.171 on gmsh's triangles), −0.010 on
    // average; h = 0.05 0.982 to 1.008, 0.040 at most (exact contact on its polygon: 0.061),
    // −0.003 on average. On h = 0.05 the medium is made again at the press's end; the slide's
    // first step is cut there as at any segment's start (it was not, and met 0.075)
    for (h, band, most_allowed) in [(0.1, 0.12, 0.2), (0.05, 0.03, 0.05)] {
        let out = slid_half(
            &format!("cylinder-slide-far-{h}"),
            &format!("params = {{ h = {h} }}"),
            false,
        );
        let (fn0, lo, hi, mean, most) = slide_forces(&out);
        assert!(
            lo > (1.0 - band) * fn0 && hi < (1.0 + band) * fn0,
            "h = {h}: F_n {lo} to {hi}, {fn0} pressed"
        );
        assert!(mean.abs() < 0.01, "h = {h}: F_t/F_n {mean} on average");
        assert!(most < most_allowed, "h = {h}: F_t/F_n {most} at most");
    }
}

/// A cylinder twice the README's (R = 0.8) on the same mesh (h = 0.1), pressed 0.15 and slid
/// 0.5 without friction. The slide's steps on the press's medium stopped at 0.053, a medium
/// cell beside the contact's front inverted and Newton then stalled there at every cut, before
/// any remake was due. A step that fails twice from one state now has the medium made again
/// there: the slide completes (measured: 35 remakes; F_n 0.959 to 1.011 of the press's 1.610;
/// F_t/F_n −0.002 on average and 0.046 at most, below h / 2R = 0.0625, the lean of a facet's
/// end; a remake changed the rim's reaction by 1.1 % at most).
#[test]
fn a_cylinder_twice_as_large_slides_its_whole_way_when_the_medium_is_made_again_where_it_stops() {
    let out = slid_half(
        "cylinder-large-slide",
        "params = { h = 0.1, R = 0.8 }",
        true,
    );
    let s = summary(&out);
    assert!(s["medium_remade"].as_u64().unwrap() > 0);
    let force = s["medium_remade_force_change"].as_f64().unwrap();
    assert!(force < 0.02, "a remake changed F by {force}");
    let (fn0, lo, hi, mean, most) = slide_forces(&out);
    assert!(
        lo > 0.95 * fn0 && hi < 1.05 * fn0,
        "F_n {lo} to {hi}, {fn0} pressed"
    );
    assert!(mean.abs() < 0.01, "F_t/F_n {mean} on average");
    assert!(most < 0.0625, "F_t/F_n {most} at most");
}

/// A medium that cannot be made again for its shape (its boundary crossing itself; asked for
/// at the fifth remake, `TMC_TEST_REMAKE_FAILS`) ends the run as at a step that fails: its
/// error says so and where, `summary.json` is written with it (before, a failed remake left
/// no summary), and the converged steps are kept. (The scene this test ran before, the
/// cylinder dragged 1.2 off the plate's end, now stalls at a slide of 0.84 as the cylinder
/// presses the medium against the end of its box, which stays where it was drawn.)
#[test]
fn a_medium_that_cannot_be_made_again_ends_the_run_with_its_summary() {
    let case = case_file(
        "cylinder-slide-cannot-be-made-again",
        "cylinder-plate.geo",
        "params = { h = 0.1 }",
        &case_body("cylinder-slide"),
    );
    let out = case.with_file_name("out");
    let o = tmc_with(&solve_args(&case, &out), &[("TMC_TEST_REMAKE_FAILS", "5!")]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the medium could not be made again at t = ")
            && e.contains("asked to fail")
            && !e.contains("going on with it as it is")
            && e.contains("converged steps up to"),
        "{e}"
    );
    let s = summary(&out);
    assert_eq!(s["converged"], false);
    let message = s["message"].as_str().unwrap();
    assert!(e.contains(message), "{message} / {e}");
    // every converged step is in the history and has its file
    let steps = s["load_steps"].as_u64().unwrap() as usize;
    assert!(steps > 20, "{steps} steps");
    assert_eq!(history(&out).1.len(), steps + 1);
    assert!(out.join(format!("step_{steps:04}.vtu")).exists());
}

/// The cylinder held at θ = 1 by its rim, the plate's bottom at 0, steady conduction through
/// the closing and sliding medium: what enters at the rim leaves at the bottom in every step
/// (across every remake), and a remake's change of the heat flow is measured.
#[test]
fn heat_crosses_a_medium_made_again_and_is_conserved() {
    let body = settled(&case_body("cylinder-slide"))
        .replace("mu = 10.0\n", "mu = 10.0\nk = 10.0\n")
        .replace("remake = true\n", "remake = true\nk = 0.01\n")
        .replace("ux = 0.0\nuy = 0.0\n", "ux = 0.0\nuy = 0.0\ntheta = 0.0\n")
        .replace(
            "[[bc]]\ngroup = \"rim\"\nuy",
            "[[bc]]\ngroup = \"rim\"\ntheta = 1.0\nramp = false\n\n[[bc]]\ngroup = \"rim\"\nuy",
        );
    let (out, s) = solved_on_readme_mesh("cylinder-slide-heat", &body);
    assert!(s["medium_remade"].as_u64().unwrap() > 0);
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (rim, bottom) = (col("Q_rim"), col("Q_bottom"));
    for r in &rows[1..] {
        assert!(r[rim] > 0.0, "heat enters at the rim: {}", r[rim]);
        assert!(
            (r[rim] + r[bottom]).abs() < 1e-8 * r[rim],
            "in {} out {}",
            r[rim],
            r[bottom]
        );
    }
    // measured: 0.67 % at most over 22 remakes (0.92 % on gmsh's triangles; 11.4 % when each
    // new cell of the closed layer carried the old J where it stood, its conductance k(J)
    // with it)
    let heat = s["medium_remade_heat_change"].as_f64().unwrap();
    assert!(heat > 0.0 && heat < 0.01, "a remake changed Q by {heat}");
}

#[test]
fn check_says_the_medium_will_be_made_again() {
    let o = tmc(&[
        "check",
        root().join("cases/cylinder-slide.toml").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(
        text.contains("medium made again as the bodies move")
            && text.contains("the next step from the state as carried"),
        "{text}"
    );
    // and whether each remake is settled first
    let settled = case_file(
        "check-settled",
        "cylinder-plate.geo",
        "params = { h = 0.1 }",
        &settled(&case_body("cylinder-slide")),
    );
    let o = tmc(&["check", settled.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(
        o.status.success() && text.contains("the mechanics settled at the same load after each"),
        "{text}"
    );
}

/// The console says what a run solves once, not again each time the medium is made again
/// (it said it before each of the README cylinder's 40-odd remakes).
#[test]
fn a_run_whose_medium_is_made_again_says_what_it_solves_once() {
    let out = scratch("out");
    let case = root().join("cases/cylinder-slide.toml");
    let o = tmc(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(summary(&out)["medium_remade"].as_u64().unwrap() > 10);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert_eq!(text.matches("physics: ").count(), 1, "{text}");
}

#[test]
fn what_remake_cannot_do_yet_check_and_solve_refuse_alike() {
    let body = case_body("cylinder-slide");
    let cases = [
        (
            "on-a-solid",
            "params = { h = 0.1 }",
            body.replace("mu = 10.0\n", "mu = 10.0\nremake = true\n"),
            "`remake` is a medium key; this region is a solid",
        ),
        (
            "heavy-medium",
            "params = { h = 0.1 }",
            body.replace("remake = true\n", "remake = true\nrho = 1e-4\n"),
            "region[2] (\"medium\"): `rho` is not carried across a remake yet: a medium made \
             again takes none (give it to the solids)",
        ),
        (
            "warm-medium",
            "params = { h = 0.1 }",
            body.replace("remake = true\n", "remake = true\nrho_c = 1.0\n"),
            "region[2] (\"medium\"): `rho_c` is not carried across a remake yet",
        ),
        (
            "quadratic",
            "order = 2\nparams = { h = 0.1 }",
            body.clone(),
            "works with linear cells only so far",
        ),
        (
            "settled-unmade",
            "params = { h = 0.1 }",
            body.replace("remake = true\n", "settle = true\n"),
            "region[2] (\"medium\"): `settle` settles the mechanics after each remake of the \
             medium; it needs `remake = true`",
        ),
        (
            "settled-solid",
            "params = { h = 0.1 }",
            body.replace("mu = 10.0\n", "mu = 10.0\nsettle = true\n"),
            "`settle` is a medium key; this region is a solid",
        ),
    ];
    // in 3D, a medium of hexahedra (the Table 2 block on its plate)
    let hex = case_body("block-plate-3d").replacen(
        "kind = \"medium\"\n",
        "kind = \"medium\"\nremake = true\n",
        1,
    );
    assert!(hex.contains("remake = true"));
    let cases = cases
        .into_iter()
        .map(|(t, o, b, w)| (t, o, b, w, "cylinder-plate.geo"));
    let hex = (
        "hexahedra",
        "",
        hex,
        "works in 3D with tetrahedra (tet4) only so far; this medium has H1 (hex8) cells",
        "block-plate-3d.geo",
    );
    for (tag, options, text, words, geo) in cases.chain([hex]) {
        let case = case_file(&format!("remake-{tag}"), geo, options, &text);
        let out = case.with_file_name("out");
        for o in [
            tmc(&["check", case.to_str().unwrap()]),
            solve_cli(&case, &out, &[]),
        ] {
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{tag}: {e}");
            assert!(e.contains(words), "{tag}: \"{words}\" not in: {e}");
        }
        assert!(
            !out.join("step_0000.vtu").exists(),
            "{tag}: nothing written"
        );
    }
}

/// `sphere-drag` without friction, its medium made again, dragged `ux` on a coarse mesh
/// (h = 0.25): the case file, in a scratch folder named `name` (a `.vtu` of the first and the
/// last state only).
fn sphere_slide(name: &str, ux: &str) -> std::path::PathBuf {
    let body = (case_body("sphere-drag"))
        .replace(
            "friction = { mu = 0.3, normal = \"auto\" }",
            "remake = true",
        )
        .replace("ux = 0.4\n", &format!("ux = {ux}\n"));
    assert!(body.contains("remake = true\n") && body.contains(&format!("ux = {ux}\n")));
    let body = body + common::ENDS_ONLY;
    case_file(name, "sphere-plate.geo", "params = { h = 0.25 }", &body)
}

/// The hemisphere of `sphere-drag` without friction, its medium of tetrahedra made again as it
/// moves, pressed and dragged half its radius on a coarse mesh: it keeps the normal force of
/// its press and meets no drag, where the Lagrangian medium's drag was 0.44 of the normal
/// force at μ = 0 (issue 68).
#[test]
fn the_sphere_slides_on_a_medium_of_tetrahedra_made_again_with_no_drag() {
    let case = sphere_slide("sphere-slide", "0.2");
    let o = tmc(&["check", case.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(
        o.status.success() && text.contains("replaced by new tetrahedra"),
        "{text}"
    );
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert!(
        s["medium_remade"].as_u64().unwrap() > 10,
        "made again as it slides"
    );
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, fx, fz, ux) = (
        col("time"),
        col("R_slider_top_x"),
        col("R_slider_top_z"),
        col("U_slider_top_x"),
    );
    let press = rows.iter().find(|r| r[t] == 1.0).expect("the press's end");
    let fn0 = -press[fz];
    let slide: Vec<&Vec<f64>> = rows.iter().filter(|r| r[t] > 1.0).collect();
    assert!(
        (slide.last().unwrap()[ux] - 0.2).abs() < 1e-12,
        "the whole drag"
    );
    let ratio: Vec<f64> = slide.iter().map(|r| r[fx] / -r[fz]).collect();
    let mean = ratio.iter().sum::<f64>() / ratio.len() as f64;
    let most = ratio.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    // measured: F_t/F_n 0.0024 on average, 0.017 at most; F_n 0.2 % below to 1.4 % above
    // the press's, 34 remakes (0.0017, 0.019, 0.7 % and 1.0 %, 50 remakes, before a thin
    // tetrahedron's pass asked only where it squeezed it; 0.004 and 0.028, 51, before the
    // penalty beside a body was weighed a tenth; 0.005 and 0.025, 50, before the symmetry plane's nodes near a
    // body were dropped; 0.003 and 0.024, 0.7 % and 0.8 %, 149 remakes, with each
    // thin tetrahedron asking at each step and the box's nodes beside a body kept where the
    // run left them); issue 68 asks at most 0.03
    assert!(
        mean.abs() < 0.01 && most < 0.03,
        "F_t/F_n {mean} on average, {most} at most"
    );
    for r in &slide {
        assert!(
            (-r[fz] / fn0 - 1.0).abs() < 0.02,
            "F_n {} against {fn0}",
            -r[fz]
        );
    }
}

/// The hemisphere of `sphere-drag` with its friction (μ = 0.3) and heat on h = 0.25, its
/// medium made again, dragged toward the end of a longer plate (x1 = 2.2) at 1.2 a unit of
/// time to t = 1.4 (a drag of 0.48). The contact's leading edge sweeps over its symmetry
/// plane's medium nodes; kept there, one was held in the closed layer between the bodies and
/// the run stopped at t = 1.3045 with Newton's residual largest at it. Dropped from the plane
/// as a body comes near, measured: the whole way, 181 slide steps, F_t/F_n 0.3006 on average,
/// 0.325 at most (the plate's dent and the nodes' passes), F_n 0.96–0.99 of the press's.
#[test]
fn a_sphere_dragged_with_friction_passes_the_nodes_of_its_symmetry_plane() {
    let body = (case_body("sphere-drag"))
        .replace(
            "friction = { mu = 0.3, normal = \"auto\" }",
            "remake = true\nfriction = { mu = 0.3, normal = \"auto\" }",
        )
        .replace("ux = 0.4\n", "ux = 1.2\n")
        .replace("end = 2.0\n", "end = 1.4\n");
    assert!(body.contains("remake = true\n") && body.contains("ux = 1.2\n"));
    assert!(body.contains("end = 1.4\n"));
    let body = body + common::ENDS_ONLY;
    let case = case_file(
        "sphere-friction-slide",
        "sphere-plate.geo",
        "params = { h = 0.25, x1 = 2.2 }",
        &body,
    );
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["time"].as_f64().unwrap(), 1.4);
    let f = |k: &str| s[k].as_f64().unwrap();
    assert_eq!(f("friction_heat"), f("friction_work"));
    let balance = f("heat_stored") - f("heat_in") - f("friction_heat");
    assert!((balance / f("friction_heat")).abs() < 1e-8, "{balance}");
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, fx, fz) = (col("time"), col("R_slider_top_x"), col("R_slider_top_z"));
    let ratio: Vec<f64> = (rows.iter())
        .filter(|r| r[t] > 1.05)
        .map(|r| r[fx] / -r[fz])
        .collect();
    let mean = ratio.iter().sum::<f64>() / ratio.len() as f64;
    // measured: 0.3006 (0.312 before the penalty beside a body was weighed a tenth)
    assert!((mean / 0.3 - 1.0).abs() < 0.03, "F_t/F_n {mean} on average");
}

/// The square pad in 3D of `cases/pad-box-slide-3d.toml` (the pad meshed at hp = 0.15 on a
/// plate at h = 0.2, the medium a box of default tetrahedra), pressed 0.12 and slid 0.45
/// without friction. Its leading face comes over a row of the plate's nodes every 0.1 of slide;
/// the slivers between that face and the row ahead, thin along the slide, started squeezed to
/// the closed layer's thickness along it, and pushed the pad back: 0.078 of the normal force at a
/// slide of 0.405, F_n up to 1.8 % over the press's. Such a sliver now starts as the open
/// medium does. Between the rows the pad's side face shears the medium beside it by the slide
/// since the last remake, and the rotation penalty there held it at 0.005 (the median); a
/// tenth of it on the cells beside a body (`remake::BESIDE`), and the open cells beside a body
/// let go of their shear at each step (`References::release_beside`). The first step after a
/// remake took the leading face over a row against 0.020 of F_n; it is now at least a twentieth
/// of the largest step, not a tenth. Measured: 0.0074 at most, 0.0021 on average, 0.0016 the
/// median, F_n within 0.4 %, 39 remakes in 131 steps (0.020, 0.0031, 0.0018, 44 in 105 at a
/// tenth; 0.020, 0.0022, 0.0011 with a remake at nearly every step; 0.023, 0.006 and about 0.005
/// before the penalty's tenth).
#[test]
fn a_square_pad_is_not_pushed_back_as_it_slides_over_the_rows_of_the_plate_s_nodes() {
    let case = square_pad_slid("pad-3d-rows", 1.45, common::ENDS_ONLY);
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, ratio, fz) = (col("time"), col("Ft_Fn_top"), col("R_top_z"));
    let pressed = -rows.iter().find(|r| r[t] == 1.0).expect("the press's end")[fz];
    let slide: Vec<&Vec<f64>> = rows.iter().filter(|r| r[t] > 1.0).collect();
    assert_eq!(slide.last().unwrap()[t], 1.45, "the whole slide");
    let most = slide.iter().fold(0.0f64, |m, r| m.max(r[ratio].abs()));
    let mean = slide.iter().map(|r| r[ratio]).sum::<f64>() / slide.len() as f64;
    let mut sizes: Vec<f64> = slide.iter().map(|r| r[ratio].abs()).collect();
    sizes.sort_by(f64::total_cmp);
    let median = sizes[sizes.len() / 2];
    assert!(
        most < 0.012 && mean < 0.004 && median < 0.002,
        "F_t/F_n {most} at most, {mean} on average, {median} the median"
    );
    for r in &slide {
        assert!(
            (-r[fz] / pressed - 1.0).abs() < 0.01,
            "F_n {} against {pressed}",
            -r[fz]
        );
    }
}

/// `cases/pad-box-slide-3d.toml` slid `end` − 1 of its width (the run ends at t = `end`), `tail`
/// added to it, in a scratch folder named `name`.
fn square_pad_slid(name: &str, end: f64, tail: &str) -> std::path::PathBuf {
    let steps = "[steps]\npath = [0.0, 1.0, 1.0]\n";
    let time = format!(
        "[time]\nend = {end}\ndt = 0.05\nlambda = [[0.0, 0.0], [1.0, 1.0], [2.0, 1.0]]\n\n[steps]\n"
    );
    let body = case_body("pad-box-slide-3d");
    assert_eq!(body.matches(steps).count(), 1);
    let text = body.replace(steps, &time) + tail;
    case_file(
        name,
        "pad-box-3d.geo",
        "params = { h = 0.2, hp = 0.15 }",
        &text,
    )
}

/// The square pad in 3D without friction stopped by Ctrl-C part way through its slide and
/// continued with `--restart`: what its medium's watch keeps (each thin tetrahedron's volume,
/// the cells on a body's edge) and the references its open cells beside a body let their shear
/// go into carry over, and the run gives the uninterrupted history to the bit.
#[test]
fn a_3d_medium_made_again_without_friction_restarts_as_if_never_stopped() {
    // slid 0.2 (0.45 before: 66–77 s of a fresh clone's `make test`)
    let case = square_pad_slid("pad-3d-restart", 1.2, "");
    let (full, stopped) = (case.with_file_name("full"), case.with_file_name("stopped"));
    let o = solve_cli(&case, &full, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    // steps 57 and 58 are followed by no remake: the checkpoint holds cells that have let go
    // of their shear since their medium was made (a checkpoint just made again holds none)
    let remakes = interrupted_after(&case, &stopped, 58);
    assert!(remakes > 0, "stopped after {remakes} remakes");
    let o = solve_cli(&case, &stopped, &["--restart"]);
    assert!(o.status.success(), "{}", stderr(&o));
    same_history_to_the_bit(&full, &stopped);
    let (a, b) = (summary(&full), summary(&stopped));
    assert_eq!(a["medium_remade"], b["medium_remade"]);
    // the restart went on across remakes of its own
    assert!(b["medium_remade"].as_u64().unwrap() > remakes, "{b}");
}

/// The hemisphere of `sphere-drag` without friction pressed alone, its medium of tetrahedra
/// made again: only as the gap closes, not at each step where a corner gmsh made beside an
/// edge across crawls toward it (19 remakes in 73 load steps before; 40 without `remake`).
#[test]
fn a_3d_press_without_friction_is_made_again_only_as_its_gap_closes() {
    let case = sphere_slide("sphere-press", "0.2");
    let text = std::fs::read_to_string(&case).unwrap();
    assert!(text.contains("end = 2.0\n"));
    std::fs::write(&case, text.replace("end = 2.0\n", "end = 1.0\n")).unwrap();
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    let (remakes, steps) = (s["medium_remade"].as_u64().unwrap(), &s["load_steps"]);
    // measured: 3 remakes, 52 load steps (2 and 49 before a crushed cell asked in 3D)
    assert!(
        (1..=3).contains(&remakes),
        "{remakes} remakes, {steps} load steps"
    );
    let (cols, rows) = history(&out);
    let t = cols.iter().position(|c| c == "time").unwrap();
    assert_eq!(rows.last().unwrap()[t], 1.0, "the whole press");
}

/// Where gmsh cannot fill the medium at a state (a flat tetrahedron where a closed layer is
/// thinnest), the run goes on a step with the medium it has and makes it again after it, up
/// to three times in a row; a fourth ends the run with its steps kept. The mesher's failures
/// are asked for (`TMC_TEST_REMAKE_FAILS`, the remakes counted from 1).
#[test]
fn a_medium_gmsh_cannot_fill_is_kept_a_step_and_made_again_after_it() {
    let case = sphere_slide("sphere-slide-mesher-fails", "0.05");
    let (tries, ends) = (case.with_file_name("tries"), case.with_file_name("ends"));
    let solve = |out: &Path, fails: &str| {
        tmc_with(&solve_args(&case, out), &[("TMC_TEST_REMAKE_FAILS", fails)])
    };
    let o = solve(&tries, "2,3,4");
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert_eq!(e.matches("going on with it as it is").count(), 3, "{e}");
    let s = summary(&tries);
    assert_eq!(s["converged"], true);
    assert!(s["medium_remade"].as_u64().unwrap() > 2, "made again after");
    let o = solve(&ends, "2,3,4,5");
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the medium could not be made again at t = ")
            && e.contains("asked to fail")
            && e.contains("converged steps up to"),
        "{e}"
    );
    let s = summary(&ends);
    assert_eq!(s["converged"], false);
    let steps = s["load_steps"].as_u64().unwrap() as usize;
    assert_eq!(history(&ends).1.len(), steps + 1);
    // up to where it ended, the steps of the run that went on, to the bit but the clock: each
    // remake made the same cells in the other process
    let ((cols, went_on), (_, ended)) = (history(&tries), history(&ends));
    let wall = cols.iter().position(|c| c == "wall_seconds").unwrap();
    for (k, (a, b)) in ended.iter().zip(&went_on).enumerate() {
        for c in (0..cols.len()).filter(|&c| c != wall) {
            assert_eq!(a[c].to_bits(), b[c].to_bits(), "row {k}, {}", cols[c]);
        }
    }
}

/// `case` solved into `stopped` and interrupted by Ctrl-C once step `step` is written: the
/// remakes its checkpoint counts.
fn interrupted_after(case: &Path, stopped: &Path, step: usize) -> u64 {
    let o = solve_interrupted_after(case, stopped, step);
    assert!(!o.status.success(), "the run was interrupted");
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(stopped.join("restart.json")).unwrap())
            .unwrap();
    checkpoint["totals"]["medium_remakes"].as_u64().unwrap()
}

#[test]
fn a_run_whose_medium_is_made_again_restarts_as_if_never_stopped() {
    // the cylinder's slide stopped by Ctrl-C once step 30 is written (the slide begins at step
    // 20 and the medium is made again every step or two from then on), then continued with
    // --restart on the mesh of the checkpoint's remake: the uninterrupted history to the bit
    let case = root().join("cases/cylinder-slide.toml");
    let dir = scratch("cylinder-slide-restart");
    let (full, stopped) = (dir.join("full"), dir.join("stopped"));
    let o = solve_cli(&case, &full, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let remakes = interrupted_after(&case, &stopped, 30);
    assert!(remakes > 0, "stopped after {remakes} remakes");
    // without the remade meshes there is nothing to continue from, and it is said
    let bare = dir.join("bare");
    std::fs::create_dir_all(&bare).unwrap();
    for e in std::fs::read_dir(&stopped).unwrap() {
        let e = e.unwrap();
        if !e.file_name().to_string_lossy().starts_with("medium") {
            std::fs::copy(e.path(), bare.join(e.file_name())).unwrap();
        }
    }
    let o = solve_cli(&case, &bare, &["--restart"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let said = format!(
        "it continues the mesh of the medium's remake {remakes}, and neither medium.json nor \
         medium-previous.json is there"
    );
    assert!(stderr(&o).contains(&said), "{}", stderr(&o));
    let o = solve_cli(&case, &stopped, &["--restart"]);
    assert!(o.status.success(), "{}", stderr(&o));
    same_history_to_the_bit(&full, &stopped);
    let (a, b) = (summary(&full), summary(&stopped));
    for key in [
        "load_steps",
        "newton_iterations",
        "medium_remade",
        "reactions",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
}

/// A run that stops where its medium was made again twice with no step between (a step that
/// fails on the new medium has it made again at once) restarts from its checkpoint: the mesh
/// the checkpoint continues is kept beside the newest. The pad in a box on quadrilaterals at
/// μ = 1 in steps of 0.1 stalls so at a drag of 0.28 (h = 0.1), the medium made 17 times, its
/// checkpoint on the 15th (in steps of 0.05 it stopped so too, at 0.38, until a closed
/// layer's crushed cells asked for remakes of their own); the restart met "it continues the
/// mesh of the medium's remake 18, and medium.json holds remake 20, medium-previous.json holds
/// remake 19" before.
#[test]
fn a_run_stopped_after_remakes_that_no_step_followed_restarts_from_its_checkpoint() {
    let body = (case_body("pad-box-slide").replace("mu = 0.3, normal", "mu = 1.0, normal"))
        .replace("initial = 0.05\nmax = 0.05", "initial = 0.1\nmax = 0.1");
    assert!(body.contains("mu = 1.0, normal") && body.contains("max = 0.1\n"));
    let case = case_file(
        "pad-box-quads-stall-restart",
        "pad-box.geo",
        "params = { h = 0.1, quads = 1 }",
        &(body + common::ENDS_ONLY),
    );
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    let stopped = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{stopped}");
    let remake_of = |file: &str| -> u64 {
        let text = std::fs::read_to_string(out.join(file)).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["remakes"].as_u64().unwrap()
    };
    let restart: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("restart.json")).unwrap()).unwrap();
    let saved = restart["totals"]["medium_remakes"].as_u64().unwrap();
    assert!(
        remake_of("medium.json") >= saved + 2,
        "the scene no longer stops two remakes past its checkpoint (remake {} after {saved}): \
         this test needs another that does",
        remake_of("medium.json")
    );
    assert_eq!(remake_of("medium-previous.json"), saved);
    // it goes on from the checkpoint and stops where it stopped, its files as they were
    let o = solve_cli(&case, &out, &["--restart"]);
    let again = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{again}");
    let at =
        |e: &str| e[e.find("load step from").expect(e)..e.find(" failed").expect(e)].to_string();
    assert_eq!(at(&again), at(&stopped), "{again}");
    assert_eq!(remake_of("medium-previous.json"), saved);
}

#[test]
fn a_medium_made_again_is_refused_several_ranks_by_name() {
    let case = root().join("cases/cylinder-slide.toml");
    let o = mpirun_tmc(2, &["check".as_ref(), case.as_os_str()]);
    assert!(!o.status.success());
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(
        text.contains("a medium made again as the bodies move (`remake`) runs on one process"),
        "{text}"
    );
}

/// The cylinder slid with friction (μ = 0.3, the slip planes from `normal = "auto"`) and its
/// frictional heat conducted out through both bodies: a remake carries each point's share of
/// its Coulomb limit and the work dissipated so far onto the new cells. The whole slide
/// completes; the friction work never drops at a remake and all of it is heat (the heat
/// balance closes to 1e-8); and F_t/F_n stays about μ (measured on h = 0.1: a time mean of
/// 0.265, swinging 0.14 … 0.39 as the cylinder's facets pass the plate's nodes, as the
/// frictionless slide swings ±0.10 about 0). The work done on the rim is not the energy kept
/// plus friction's: a remake lets go of what the medium stored (measured: 11 % of the work
/// here, 13 % on the frictionless slide), which no column counts yet. Stopped by Ctrl-C part
/// way through the slide and continued with `--restart`, the run gives the uninterrupted
/// history to the bit (the Krylov count of its first step aside): the checkpoint holds the
/// carried friction of the last remake.
#[test]
fn friction_and_its_heat_carry_across_a_medium_made_again() {
    let body = case_body("cylinder-slide")
        .replace("mu = 10.0\n", "mu = 10.0\nk = 10.0\nrho_c = 1.0\n")
        .replace(
            "remake = true\n",
            "remake = true\nk = 0.01\nfriction = { mu = 0.3, normal = \"auto\" }\n",
        )
        .replace(
            "ux = 0.0\nuy = 0.0\n",
            "ux = 0.0\nuy = 0.0\ntheta = 0.0\nramp = false\n",
        );
    let steps = "[steps]\npath = [0.0, 1.0, 1.0]\ninitial = 0.05\nmax = 0.05\n";
    assert!(body.contains(steps) && body.contains("friction = {"));
    let body = body.replace(
        steps,
        "[time]\nend = 2.0\ndt = 0.05\nlambda = [[0.0, 0.0], [1.0, 1.0], [2.0, 1.0]]\n",
    );
    let (out, s) = solved_on_readme_mesh("cylinder-slide-friction", &body);
    let f = |key: &str| {
        s[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key}: {}", s[key]))
    };
    assert_eq!(f("time"), 2.0);
    assert!(
        s["medium_remade"].as_u64().unwrap() > 10,
        "{}",
        s["medium_remade"]
    );
    let (work, heat) = (f("friction_work"), f("friction_heat"));
    assert!(work > 0.0 && heat == work, "work {work}, heat {heat}");
    let joined = s["heat_joined"].as_f64().unwrap_or(0.0);
    let open = f("heat_stored") - f("heat_in") - heat - joined;
    assert!(
        open.abs() < 1e-8 * heat,
        "the heat balance is open by {open}"
    );
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, w) = (col("time"), col("friction_work"));
    for pair in rows.windows(2) {
        assert!(
            pair[1][w] >= pair[0][w],
            "the friction work dropped at t = {}: {} then {}",
            pair[1][t],
            pair[0][w],
            pair[1][w]
        );
    }
    let (_, _, _, mean, _) = slide_forces(&out);
    assert!((mean - 0.3).abs() < 0.05, "F_t/F_n {mean} over the slide");
    // the slide begins after step 20; the medium is made again in bursts as the faces'
    // nodes pass each other, six times by step 55 and nine times after it
    let stopped = out.with_file_name("stopped");
    let case = out.with_file_name("case.toml");
    let remakes = interrupted_after(&case, &stopped, 55);
    assert!(remakes > 5, "stopped after {remakes} remakes");
    let o = solve_cli(&case, &stopped, &["--restart"]);
    assert!(o.status.success(), "{}", stderr(&o));
    same_state_to_the_bit(&out, &stopped);
    let again = summary(&stopped);
    for key in [
        "load_steps",
        "newton_iterations",
        "medium_remade",
        "friction_work",
        "friction_heat",
        "heat_stored",
        "heat_in",
    ] {
        assert_eq!(s[key], again[key], "{key}");
    }
}

/// `cases/pad-box-slide.toml` (the pad in a box of medium drawn as a user draws it, dragged
/// one pad width) on triangles of h = 0.2, in the scratch folder `name`, with `body` changed
/// by `edit`: per accepted step of the drag, the drive's slide, F_t/F_n and F_n, and F_n at
/// the press's end.
fn pad_in_a_box(name: &str, edit: impl Fn(String) -> String) -> (Vec<[f64; 3]>, f64) {
    pad_in_a_box_on(name, "params = { h = 0.2 }", edit)
}

/// [`pad_in_a_box`] on the mesh the `[mesh_options]` line `params` asks `geo/pad-box.geo`
/// for.
fn pad_in_a_box_on(
    name: &str,
    params: &str,
    edit: impl Fn(String) -> String,
) -> (Vec<[f64; 3]>, f64) {
    let (drag, pressed, _) = pad_in_a_box_run(name, params, edit);
    assert!(
        (drag.last().unwrap()[0] - 1.0).abs() < 1e-12,
        "the whole drag"
    );
    (drag, pressed)
}

/// [`pad_in_a_box_on`] whatever the drag's length, with the run's summary.
fn pad_in_a_box_run(
    name: &str,
    params: &str,
    edit: impl Fn(String) -> String,
) -> (Vec<[f64; 3]>, f64, serde_json::Value) {
    let body = edit(case_body("pad-box-slide")) + common::ENDS_ONLY;
    let case = case_file(name, "pad-box.geo", params, &body);
    let out = case.with_file_name("out");
    let o = solve_cli(&case, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert!(s["medium_remade"].as_u64().unwrap() > 5, "made again");
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, ux, fx, fy) = (col("time"), col("U_top_x"), col("R_top_x"), col("R_top_y"));
    let pressed = -rows.iter().find(|r| r[t] == 1.0).expect("the press's end")[fy];
    let drag: Vec<[f64; 3]> = (rows.iter().filter(|r| r[t] > 1.0))
        .map(|r| [r[ux], r[fx] / -r[fy], -r[fy]])
        .collect();
    assert_eq!(rows.last().unwrap()[t], 2.0, "the path's end");
    (drag, pressed, s)
}

/// F_t/F_n at each step of a pad in a box's `drag` (as [`pad_in_a_box`] gives it) once the
/// pad slips (a slide of 0.05 on), with its mean, least and largest.
fn slipping(drag: &[[f64; 3]]) -> (Vec<f64>, f64, f64, f64) {
    let ratios: Vec<f64> = (drag.iter().filter(|d| d[0] > 0.05))
        .map(|d| d[1])
        .collect();
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    let (lo, hi) = (ratios.iter()).fold((f64::MAX, 0.0f64), |(l, h), r| (l.min(*r), h.max(*r)));
    (ratios, mean, lo, hi)
}

/// Issue 68's pad drawn as users draw it: the medium a box around the pad, default triangles,
/// no layer of its own and no expert key. Before its corner was joined over the plate's face
/// at a remake (`mesh::remesh::fans`) and the box's own faces were placed anew
/// (`model::remake::Medium::own_places`), it stalled at a drag of 0.11 frictionless and 0.19
/// at μ = 0.3 (on h = 0.1), its leading corner's cells turned inside out.
#[test]
fn a_pad_in_a_box_of_medium_slides_its_width_frictionless_and_at_mu() {
    let (drag, pressed) = pad_in_a_box("pad-box-frictionless", |b| {
        let b = b.replace("friction = { mu = 0.3, normal = \"auto\" }\n", "");
        assert!(!b.contains("friction"));
        b
    });
    // measured: F_t/F_n 0.003 on average, 0.007 at most (0.005 and 0.014 with the rotation
    // penalty per current volume); F_n within 2 % of the press's
    let mean = drag.iter().map(|d| d[1]).sum::<f64>() / drag.len() as f64;
    let most = drag.iter().fold(0.0f64, |m, d| m.max(d[1].abs()));
    assert!(mean.abs() < 0.01 && most < 0.02, "F_t/F_n {mean}, {most}");
    for d in &drag {
        assert!(
            (d[2] / pressed - 1.0).abs() < 0.02,
            "F_n {} of {pressed}",
            d[2]
        );
    }
    // at μ = 0.3, once the pad slips (a slide of 0.05): measured 0.3051 on average, 0.290 to
    // 0.312 (on h = 0.1: 0.3033, 0.2964 to 0.3071, every step within 3 % of μ). With the
    // rotation penalty per current volume (a closed layer's pull) 0.3175, 0.302 to 0.357;
    // with the plane's stress F (N⊗τ + τ⊗N) too 0.319, 0.296 to 0.366; before the closed
    // layers took their slide into their references at every step, 0.344, 0.296 to 0.495
    let (drag, _) = pad_in_a_box("pad-box-mu", |b| b);
    let (_, mean, lo, hi) = slipping(&drag);
    assert!(
        (0.295..0.315).contains(&mean) && lo > 0.285 && hi < 0.32,
        "F_t/F_n {mean} on average, {lo} to {hi}"
    );
}

/// The pad in a box at μ = 1 on triangles of h = 0.1, without continuation, stalls at a slide
/// of 0.15: its leading corner digs a dent in the plate it cannot climb out of
/// (docs/notes/2026-12-03-mu-1-and-mu-0.1-on-the-pad-in-a-box.md), on the medium made again
/// there too, which the run tries before it stops. The run says what carries
/// it through, and what it says is taken: a mass density on the solids (measured with `rho = 1e-4` on both: the whole drag,
/// 346 steps; the 3D pad at μ = 0.1 likewise, docs/notes/2026-12-04-a-sigterm-in-metis-and-
/// a-hint-taken.md), not on every region, since a medium made again takes none (before, the
/// hint asked for it on every region, and the case so changed was refused).
#[test]
fn a_stalled_drag_over_a_medium_made_again_names_a_mass_density_on_the_solids() {
    // settled after each remake: the remake before the stall leaves it unsettled
    let (case, e) = pad_box_stall(
        "pad-box-stall",
        (
            "remake = true\nfriction = { mu = 0.3, normal",
            "remake = true\nsettle = true\nfriction = { mu = 1.0, normal",
        ),
    );
    assert!(
        e.contains("leading corner digs into the face it slides on")
            && e.contains("`rho` on every solid can carry it through")
            && e.contains("a medium made again takes none"),
        "{e}"
    );
    // the remake before the stall left the mechanics unsettled (the corner's dent): said
    // once without -v, and counted
    assert!(
        e.contains("warning: the mechanics did not settle on the medium made again at t = 1.15"),
        "{e}"
    );
    let s = summary(&case.with_file_name("out"));
    assert!(s["medium_remade_unsettled"].as_u64().unwrap() >= 1, "{s}");
    // where the step would have stopped it, the run made the medium again first, once
    assert_eq!(s["medium_remade_to_go_on"], 1, "{s}");
    assert!(
        e.contains("failed at the shortest step")
            && e.contains("to go on")
            && e.contains("it failed so on the medium made again at this state too"),
        "{e}"
    );
    // as the hint says: taken on the solids, refused on the medium too
    let with_rho = |groups: &[&str]| {
        let mut text = std::fs::read_to_string(&case).unwrap();
        for g in groups {
            let group = format!("group = \"{g}\"\n");
            assert!(text.contains(&group), "{g}");
            text = text.replace(&group, &format!("{group}rho = 1e-4\n"));
        }
        let changed = case.with_file_name(format!("rho-{}.toml", groups.len()));
        std::fs::write(&changed, text).unwrap();
        tmc(&["check", changed.to_str().unwrap()])
    };
    let o = with_rho(&["plate", "pad"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = with_rho(&["plate", "pad", "medium"]);
    assert!(
        !o.status.success() && stderr(&o).contains("`rho`"),
        "{}",
        stderr(&o)
    );
}

/// The pad in a box at μ = 1 on triangles of h = 0.1, dragged 0.4: where Newton stalls (the
/// test above) the step is taken by pseudo-transient continuation, and once the pad slips
/// (a slide of 0.12 on) F_t/F_n is μ on average within 3 %. Measured: 0.980 on average,
/// 0.956 to 1.097 (the leading corner passing the plate's nodes, 0.1 apart), 3 steps or
/// settlings taken by continuation and one settling neither took, 121 steps in all; F_n up to
/// 1.18 of the press's as the pad tips onto its leading corner.
#[test]
fn a_pad_in_a_box_at_mu_1_slides_past_its_stall_by_continuation() {
    let (drag, pressed, s) = pad_in_a_box_run("pad-box-mu-1", "params = { h = 0.1 }", |b| {
        let b = b.replace("mu = 0.3, normal", "mu = 1.0, normal");
        assert_eq!(b.matches("ux = 1.0\n").count(), 1);
        b.replace("ux = 1.0\n", "ux = 0.4\n")
    });
    assert!(s["continued_steps"].as_u64().unwrap() >= 1, "{s}");
    assert!(
        (drag.last().unwrap()[0] - 0.4).abs() < 1e-12,
        "the whole drag"
    );
    let slipping: Vec<f64> = (drag.iter().filter(|d| d[0] > 0.12))
        .map(|d| d[1])
        .collect();
    let mean = slipping.iter().sum::<f64>() / slipping.len() as f64;
    let (lo, hi) = (slipping.iter()).fold((f64::MAX, 0.0f64), |(l, h), r| (l.min(*r), h.max(*r)));
    assert!(
        (mean - 1.0).abs() < 0.03 && lo > 0.94 && hi < 1.12,
        "F_t/F_n {mean} on average, {lo} to {hi}"
    );
    assert!(drag.iter().all(|d| d[2] > 0.95 * pressed), "F_n {pressed}");
}

/// A press that cannot step, with friction in the medium, is not told what carries a drag:
/// the pad in a box pressed in one step of two Newton iterations, with no room to cut it. The
/// same scene stalled in its drag is told (the test above).
#[test]
fn a_stalled_press_is_not_told_what_carries_a_drag() {
    let (_, e) = pad_box_stall(
        "pad-box-press-stall",
        (
            "initial = 0.05\nmax = 0.05",
            "initial = 1.0\nmax = 1.0\nmin = 0.6\nmax_iter = 2",
        ),
    );
    assert!(e.contains("the 0 converged steps"), "{e}");
    assert!(!e.contains("with friction") && !e.contains("`rho`"), "{e}");
}

/// `cases/pad-box-slide.toml` (h = 0.1) with one edit `(from, to)` and no continuation
/// (`[steps] continuation = false`), solved in a scratch folder named `name` (not quiet: its
/// warnings too), where it must stop: the case file and what the run said.
fn pad_box_stall(name: &str, (from, to): (&str, &str)) -> (std::path::PathBuf, String) {
    let body = case_body("pad-box-slide").replace("[steps]\n", "[steps]\ncontinuation = false\n");
    assert_eq!(body.matches(from).count(), 1, "{from}");
    let case = case_file(
        name,
        "pad-box.geo",
        "params = { h = 0.1 }",
        &body.replace(from, to),
    );
    let out = case.with_file_name("out");
    let o = tmc(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    (case, e)
}

/// The pad in a box dragged past the end of the box of medium drawn around it
/// (`geo/pad-box.geo` with its plate and box 3 long, on h = 0.2, frictionless, dragged two of
/// its widths): its face comes up against the box's free side, where the medium ends. The run
/// says so when it happens, and its stop names it. Measured: said at a drag of 1.45 (the
/// face 0.05 before the box's end, the side 0.07 from it), the stop at 1.52, its corner past
/// the plate's end. Before, the side was pushed ahead of the pad (3.5 past where it was drawn
/// at μ = 0.3 on the shipped box dragged six widths) and the stop told of friction, or of
/// nothing. The same drag on the box as shipped (7 long) is told nothing.
#[test]
fn a_pad_dragged_past_the_end_of_its_box_is_told_where_the_medium_ends() {
    let body =
        case_body("pad-box-slide").replace("friction = { mu = 0.3, normal = \"auto\" }\n", "");
    assert!(!body.contains("friction") && body.contains("ux = 1.0\n"));
    let body = body.replace("ux = 1.0\n", "ux = 2.0\n");
    let solve = |name: &str, length: f64| {
        let params = format!("params = {{ h = 0.2, L = {length} }}");
        let case = case_file(name, "pad-box.geo", &params, &body);
        let out = case.with_file_name("out");
        let o = tmc(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        // the warnings go to the standard error, as the error does; summary.json keeps it
        let summary = common::summary(&out);
        (
            o.status.success(),
            stderr(&o),
            summary["medium_edge_reached"].clone(),
        )
    };
    let (done, said, reached) = solve("pad-past-its-box", 3.0);
    assert!(!done, "{said}");
    let told = "the solid \"pad\" came up against the edge of the medium drawn around it";
    let line = (said.lines())
        .find(|l| l.contains(told))
        .unwrap_or_else(|| panic!("{said}"));
    assert!(
        line.starts_with("warning: step") && line.contains("draw the medium past where"),
        "{line}"
    );
    // when: the pad's leading face (drawn at x = 1.5, dragged 2 over t from 1 to 2) within a
    // cell (0.2) of the box's end at x = 3
    let t: f64 = (line.split("(t = ").nth(1))
        .and_then(|r| r.split(')').next())
        .unwrap()
        .parse()
        .unwrap();
    let face = 1.5 + 2.0 * (t - 1.0);
    assert!(
        (2.8..3.05).contains(&face),
        "told with the pad's face at x = {face}: {line}"
    );
    // the same step and time in summary.json, a node of the box's end within a cell of the
    // pad's face
    let step = (line.split("step ").nth(1))
        .and_then(|r| r.split(' ').next())
        .unwrap();
    assert_eq!(reached["solid"], "pad", "{reached}");
    assert_eq!(reached["step"].to_string(), step, "{reached}");
    assert!(
        (reached["time"].as_f64().unwrap() - t).abs() < 1e-5,
        "{reached}"
    );
    let (x, distance) = (
        reached["at"][0].as_f64().unwrap(),
        reached["distance"].as_f64().unwrap(),
    );
    assert!(
        (2.8..3.2).contains(&x) && distance > 0.0 && distance < 0.2,
        "{reached}"
    );
    let e = (said.lines())
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("{said}"));
    assert!(
        e.contains("came up against the edge of the medium drawn around it at step")
            && e.contains("draw the medium past where the solid goes")
            && !e.contains("friction"),
        "{e}"
    );
    let (done, said, reached) = solve("pad-inside-its-box", 7.0);
    assert!(done && !said.contains("warning"), "{said}");
    assert!(reached.is_null(), "{reached}");
}

/// The pad in a box on quadrilaterals (`quads = 1`, h = 0.1), at μ = 0.3. Its medium is made
/// again, into triangles, as soon as a quadrilateral has closed thin: before, the pad's
/// leading corner went through the plate's face inside the one quadrilateral across the gap
/// before the first remake was due, and the drag stopped at a slide of 0.02 (0.1 on h = 0.2).
/// Measured once slipping (a slide of 0.05 on): F_t/F_n 0.3037 on average, 0.2913 to 0.3165,
/// one step of 78 outside 3 % of μ (the second of the slip), on the triangles' band.
#[test]
fn a_pad_in_a_box_of_quadrilaterals_slides_its_width_at_mu() {
    let (drag, pressed) =
        pad_in_a_box_on("pad-box-quads", "params = { h = 0.1, quads = 1 }", |b| b);
    assert!(pressed > 0.0);
    let (slipping, mean, lo, hi) = slipping(&drag);
    let outside = slipping
        .iter()
        .filter(|r| (*r / 0.3 - 1.0).abs() > 0.03)
        .count();
    assert!(
        (0.295..0.315).contains(&mean) && lo > 0.285 && hi < 0.32 && outside <= 2,
        "F_t/F_n {mean} on average, {lo} to {hi}, {outside} of {} outside 3 %",
        slipping.len()
    );
}

/// K₀, the modified Bessel function of the second kind of order 0, for 0 < x ≤ 10: its
/// series, K₀(x) = −(ln(x/2) + γ) I₀(x) + Σₖ (x²/4)ᵏ/(k!)² Hₖ (Hₖ the harmonic numbers),
/// which loses about 8 of 16 digits to cancellation by x = 10.
fn k0(x: f64) -> f64 {
    assert!(x > 0.0 && x <= 10.0, "K0 at {x}");
    let y = x * x / 4.0;
    let (mut term, mut h) = (1.0, 0.0);
    let (mut i0, mut rest) = (1.0, 0.0);
    for k in 1..80 {
        term *= y / (k * k) as f64;
        h += 1.0 / k as f64;
        i0 += term;
        rest += term * h;
    }
    -((x / 2.0).ln() + 0.577_215_664_901_532_9) * i0 + rest
}

/// ∫ₐᵇ f(u) K₀(|u|) du, K₀'s logarithm at u = 0 taken away by u = ±s² (two-point Gauss
/// over `n` intervals in s on each side of 0).
fn with_k0(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let n = 400;
    let side = |lo: f64, hi: f64, sign: f64| {
        let (sa, sb) = (lo.max(0.0).sqrt(), hi.max(0.0).sqrt());
        if sb <= sa {
            return 0.0;
        }
        let h = (sb - sa) / n as f64;
        let g = 0.5 / 3f64.sqrt();
        (0..n)
            .flat_map(|i| [0.5 - g, 0.5 + g].map(move |o| sa + h * (i as f64 + o)))
            .map(|s| h / 2.0 * 2.0 * s * f(sign * s * s) * k0(s * s))
            .sum::<f64>()
    };
    side(a, b, 1.0) + side(-b, -a, -1.0)
}

/// Jaeger's moving band heat source (1942): a flux q over |x| < l of the surface of a
/// half-space (conductivity k, diffusivity κ) that moves along +x at the speed v, at its
/// steady state. The surface temperature at x (from the band's centre, + ahead):
/// θ(x) = 2κq/(πkv) ∫ e^(−u) K₀(|u|) du over u from v(x − l)/2κ to v(x + l)/2κ.
fn jaeger_band(x: f64, [q, l, k, kappa, v]: [f64; 5]) -> f64 {
    let s = v / (2.0 * kappa);
    2.0 * kappa * q / (std::f64::consts::PI * k * v)
        * with_k0(s * (x - l), s * (x + l), |u| (-u).exp())
}

#[test]
fn the_k0_helper_and_its_integral_are_accurate() {
    // A&S table 9.8 and ∫₀^∞ e^(−pu) K₀(u) du = arccosh(p)/√(p² − 1) (1 at p = 1)
    for (x, v) in [
        (0.1, 2.427_069_024_702_017),
        (1.0, 0.421_024_438_240_708_3),
        (5.0, 3.691_098_334_042_594e-3),
    ] {
        assert!((k0(x) - v).abs() < 1e-9 * v, "K0({x}) = {}", k0(x));
    }
    for (p, v) in [(1.0, 1.0), (2.0, 2f64.acosh() / 3f64.sqrt())] {
        let i = with_k0(0.0, 10.0, |u| (-p * u).exp());
        assert!((i - v).abs() < 1e-5, "p = {p}: {i} against {v}");
    }
}

/// Issue 68's heat carried across a medium made again: `cases/pad-flash.toml`, the pad in a
/// box of medium dragged two of its widths at the speed v = 1 over a conducting plate (κ =
/// 0.1, the Péclet number v l / 2κ = 2.5 for the half-width l = 0.5) with friction μ = 0.3,
/// its medium made again some eighty times. The friction's heat enters the plate (the pad
/// barely conducts and stores none); the plate's face under the pad reaches the flash
/// temperature of Jaeger's moving band heat source, whose flux is the friction's power
/// spread over the pad's width: measured, its mean over the band 0.9 % below Jaeger's (with
/// steps of half the size 1.0 % below; on h = 0.05 0.4 % above, on h = 0.2 4.3 % below).
/// Its peak stands 9 % below Jaeger's (7 % on h = 0.05): the pad's leading edge presses 1.3
/// times the mean and its trailing one a third of it, where Jaeger's flux is even. Across
/// every remake the heat balance closes, no remake changes a heat flow by 1 % (0.0064 %
/// measured), and F_t/F_n holds μ within 3 % once the pad slips (0.2944 to 0.3071 measured
/// over 180 steps).
#[test]
fn a_pad_dragged_over_a_conducting_plate_reaches_jaeger_s_flash_temperature() {
    let (s, out) = solve_text_opts(
        "pad-flash",
        "pad-box.geo",
        "params = { h = 0.1, d = 1.0, L = 5 }",
        &(case_body("pad-flash") + ENDS_ONLY),
    );
    assert_eq!(s.time, 2.5);
    assert!(s.medium_remade > 50, "made again {} times", s.medium_remade);
    let totals = summary(&out);
    let f = |key: &str| totals[key].as_f64().unwrap();
    let heat = f("friction_heat");
    assert!(heat > 0.0 && heat == f("friction_work"));
    let open = f("heat_stored") - f("heat_in") - heat;
    assert!(
        open.abs() < 1e-8 * heat,
        "the heat balance is open by {open}"
    );
    // what a remake changes of a group's heat flow (measured: 0.0064 % at most)
    let flow = f("medium_remade_heat_change");
    assert!(flow > 0.0 && flow < 0.01, "a remake changed Q by {flow}");
    // F_t/F_n once slipping, and the friction's power over the last 0.1 of the drag
    let (cols, rows) = history(&out);
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let (t, ux, fx, fy, w) = (
        col("time"),
        col("U_top_x"),
        col("R_top_x"),
        col("R_top_y"),
        col("friction_work"),
    );
    for r in rows.iter().filter(|r| r[t] > 0.5 && r[ux] > 0.05) {
        let ratio = r[fx] / -r[fy];
        assert!(
            (ratio / 0.3 - 1.0).abs() < 0.03,
            "F_t/F_n {ratio} at t = {}",
            r[t]
        );
    }
    let last = rows.last().unwrap();
    let before = rows.iter().rfind(|r| r[t] <= last[t] - 0.1).unwrap();
    let power = (last[w] - before[w]) / (last[t] - before[t]);
    // the band: the pad's underside where it stands; the plate's face under it
    let vtu = out.join(format!("step_{:04}.vtu", s.load_steps));
    let (u, at) = (point_array(&vtu, "u"), point_array(&vtu, "position"));
    let node = |i: usize| {
        (
            at[3 * i] - u[3 * i],
            at[3 * i + 1] - u[3 * i + 1],
            at[3 * i],
        )
    };
    let on = |y: f64, x: std::ops::RangeInclusive<f64>| {
        let mut p: Vec<(f64, usize)> = (0..at.len() / 3)
            .map(node)
            .enumerate()
            .filter(|(_, (x0, y0, _))| (y0 - y).abs() < 1e-9 && x.contains(x0))
            .map(|(i, (_, _, x))| (x, i))
            .collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p
    };
    let pad = on(1.1, 0.5 - 1e-9..=1.5 + 1e-9);
    let (left, right) = (pad[0].0, pad.last().unwrap().0);
    let (centre, l) = ((left + right) / 2.0, (right - left) / 2.0);
    let theta = point_array(&vtu, "theta");
    let face: Vec<(f64, f64)> = (on(1.0, 0.0..=5.0).into_iter())
        .map(|(x, i)| (x - centre, theta[i]))
        .collect();
    let at_x = |x: f64| {
        let k = face.partition_point(|p| p.0 < x).clamp(1, face.len() - 1);
        let ((x0, t0), (x1, t1)) = (face[k - 1], face[k]);
        t0 + (t1 - t0) * (x - x0) / (x1 - x0)
    };
    let band = [power / (2.0 * l), l, 1.0, 0.1, 1.0];
    let xs: Vec<f64> = (0..=100).map(|i| -l + 2.0 * l * i as f64 / 100.0).collect();
    let mean = |g: &dyn Fn(f64) -> f64| {
        (xs.windows(2))
            .map(|p| (g(p[0]) + g(p[1])) / 2.0 * (p[1] - p[0]))
            .sum::<f64>()
            / (2.0 * l)
    };
    let (ours, jaeger) = (mean(&at_x), mean(&|x| jaeger_band(x, band)));
    assert!(
        (ours / jaeger - 1.0).abs() < 0.05,
        "the flash temperature {ours} against Jaeger's {jaeger}"
    );
    let hottest = (xs.iter().copied())
        .max_by(|a, b| at_x(*a).total_cmp(&at_x(*b)))
        .unwrap();
    let (hot, peak) = (
        at_x(hottest),
        xs.iter().map(|&x| jaeger_band(x, band)).fold(0.0, f64::max),
    );
    assert!(
        hottest < 0.0 && (hot / peak - 1.0).abs() < 0.12,
        "the hottest point at {hottest} of the band, {hot} against Jaeger's {peak}"
    );
}
