//! End-to-end runs of the `tmc` binary and its error messages for bad input.

#![allow(non_snake_case, clippy::needless_range_loop)]

use crate::common;
use common::*;
use std::path::Path;
use std::process::{Command, Output};

#[test]
fn mesh_then_solve_2d_and_3d() {
    let dir = scratch("cli-e2e");
    for (geo, case) in [("plate-hole", "plate-hole"), ("bar3d", "bar3d-stretch")] {
        let msh = dir.join(format!("{geo}.msh"));
        let o = tmc(&[
            "mesh",
            &format!("geo/{geo}.geo"),
            "-o",
            msh.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(msh.is_file());
        let out = dir.join(case);
        let o = tmc(&[
            "solve",
            &format!("cases/{case}.toml"),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let s = summary(&out);
        assert_eq!(s["converged"], true);
        for key in [
            "dofs",
            "load_steps",
            "newton_iterations",
            "rejected_iterations",
            "linear_solves",
            "wall_seconds",
            "assembly_seconds",
            "solver_seconds",
            "output_seconds",
            "probes",
            "min_J",
            "reactions",
            "physics",
        ] {
            assert!(s.get(key).is_some(), "summary.json lacks {key}");
        }
        let steps = s["load_steps"].as_u64().unwrap() as usize;
        assert!(out.join(format!("step_{steps:04}.vtu")).is_file());
        let pvd = std::fs::read_to_string(out.join(format!("{case}.pvd"))).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), steps + 1);
        let (_, rows) = history(&out);
        assert_eq!(
            rows.len(),
            steps + 1,
            "one history row per converged step plus the initial state"
        );
    }
}

#[test]
fn plate_hole_demo_is_in_equilibrium_and_conserves_heat() {
    let (s, _) = solve_case("plate-hole");
    assert!(s.physics.heat_to_mechanics && s.physics.mechanics_to_heat);
    let (fl, fr) = (s.reactions["left"]["x"], s.reactions["right"]["x"]);
    assert!(fr > 0.5, "pulling needs a force: {fr}");
    assert!((fl + fr).abs() < 1e-9 * fr, "force balance {fl} + {fr}");
    let (ql, qr) = (s.reactions["left"]["heat"], s.reactions["right"]["heat"]);
    assert!(
        qr > 0.0 && (ql + qr).abs() < 1e-9 * qr,
        "heat balance {ql} + {qr}"
    );
    // the hole (diameter 0.5) is stretched along the pull and narrows across it
    let h = s.probes["hole_height"];
    assert!(h > 0.45 && h < 0.5 + 0.05, "{h}");
}

fn write_case(name: &str, text: &str) -> std::path::PathBuf {
    let dir = scratch(&format!("bad-{name}"));
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

const GOOD: &str = r#"mesh = "MESH"

[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0

[[bc]]
group = "left"
ux = 0.0

[[bc]]
group = "origin"
uy = 0.0

[[bc]]
group = "right"
ux = 0.2
"#;

fn case_with(name: &str, edit: impl Fn(&str) -> String) -> (Output, std::path::PathBuf) {
    let slab = root().join("geo/slab.geo");
    let text = edit(&GOOD.replace("MESH", slab.to_str().unwrap()));
    let p = write_case(name, &text);
    let out = p.parent().unwrap().join("out");
    (
        tmc(&[
            "solve",
            p.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ]),
        p,
    )
}

#[test]
fn good_case_runs() {
    let (o, _) = case_with("good", |t| t.to_string());
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_bad_idle_threads_setting_is_refused_and_the_good_ones_run() {
    // unset: the default (spin while there is work, at most 50 ms without)
    let (o, p) = case_with("idle", |t| t.to_string());
    assert!(o.status.success(), "unset: {}", stderr(&o));
    let out = p.parent().unwrap().join("out");
    let args = common::solve_args(&p, &out);
    let with = |v: &str| tmc_with(&args, &[("TMC_IDLE_THREADS", v)]);
    let o = with("nap");
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("TMC_IDLE_THREADS") && e.contains("\"nap\""),
        "{e}"
    );
    for v in ["spin", "sleep", "20"] {
        let o = with(v);
        assert!(o.status.success(), "{v}: {}", stderr(&o));
    }
    // the option, named in --help with its default and the variable
    let mut flag = args.to_vec();
    flag.extend(["--idle-threads", "sleep"]);
    let o = tmc_with(&flag, &[]);
    assert!(o.status.success(), "--idle-threads sleep: {}", stderr(&o));
    let help = tmc_with(&["solve", "--help"], &[]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("--idle-threads")
            && help.contains("TMC_IDLE_THREADS")
            && help.contains("[default: 50]"),
        "{help}"
    );
}

#[test]
fn unknown_key_is_named_with_file_and_line() {
    let (o, p) = case_with("unknown", |t| t.replace("mu = 10.0", "mu = 10.0\nnu = 0.3"));
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains(p.to_str().unwrap()) && e.contains("nu") && e.contains("line 8"),
        "{e}"
    );
}

#[test]
fn missing_group_lists_the_available_ones() {
    let (o, p) = case_with("missing", |t| {
        t.replace("group = \"right\"", "group = \"rihgt\"")
    });
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains(&format!("{}:18", p.display()))
            && e.contains("\"rihgt\" is not in the mesh")
            && e.contains("\"right\""),
        "{e}"
    );
}

#[test]
fn wrong_dimension_groups_are_refused() {
    let (o, _) = case_with("dim-region", |t| {
        t.replacen("group = \"solid\"", "group = \"left\"", 1)
    });
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("region[0]: group \"left\" has dimension 1"),
        "{e}"
    );
    let (o, _) = case_with("dim-bc", |t| {
        t.replace("group = \"right\"", "group = \"solid\"")
    });
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("is a 2D group of cells"),
        "{e}"
    );
    let (o, _) = case_with("traction-on-point", |t| {
        t.replace("uy = 0.0", "traction = [1.0, 0.0]")
    });
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("need a 1D boundary group"),
        "{e}"
    );
}

#[test]
fn non_positive_moduli_are_refused() {
    let (o, _) = case_with("negative-k", |t| t.replace("K = 20.0", "K = -1.0"));
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("`K` must be positive") && e.contains(".toml:6:"),
        "{e}"
    );
    let (o, _) = case_with("zero-mu", |t| t.replace("mu = 10.0", "mu = 0.0"));
    assert!(!o.status.success() && stderr(&o).contains("`mu` must be positive"));
}

#[test]
fn bad_convection_conditions_are_refused_with_file_line_and_key() {
    for (tag, extra, words) in [
        (
            "h-negative",
            "h = -1.0\ntheta_inf = 20.0",
            "`h` must be finite and ≥ 0",
        ),
        (
            "h-nan",
            "h = nan\ntheta_inf = 20.0",
            "`h` must be finite and ≥ 0",
        ),
        ("h-alone", "h = 2.0", "needs `theta_inf`"),
        ("ambient-alone", "theta_inf = 2.0", "give `h` too"),
        (
            "ambient-inf",
            "h = 1.0\ntheta_inf = inf",
            "`theta_inf` must be finite",
        ),
        (
            "h-and-theta",
            "theta = 5.0\nh = 1.0\ntheta_inf = 0.0",
            "cannot also convect",
        ),
    ] {
        let (o, p) = case_with(tag, |t| format!("{t}\n[[bc]]\ngroup = \"top\"\n{extra}\n"));
        let e = stderr(&o);
        let file = p.file_name().unwrap().to_str().unwrap();
        assert!(
            !o.status.success() && e.contains(words) && e.contains(&format!("{file}:2")),
            "{tag}: {e}"
        );
    }
    // a point group cannot convect in 2D: it needs a curve
    let (o, _) = case_with("h-on-point", |t| {
        format!("{t}\n[[bc]]\ngroup = \"origin\"\nh = 1.0\ntheta_inf = 0.0\n")
    });
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("convection `h` needs a 1D boundary group"),
        "{e}"
    );
}

#[test]
fn bad_heat_capacities_and_time_sections_are_refused_with_file_line_and_key() {
    type Edit = dyn Fn(&str) -> String;
    let cases: [(&str, &Edit, &str); 9] = [
        (
            "rho-c-zero",
            &|t| t.replace("mu = 10.0", "mu = 10.0\nrho_c = 0.0"),
            "`rho_c` must be positive and finite",
        ),
        (
            "rho-c-negative",
            &|t| t.replace("mu = 10.0", "mu = 10.0\nrho_c = -3.0"),
            "`rho_c` must be positive and finite",
        ),
        (
            "rho-c-inf",
            &|t| t.replace("mu = 10.0", "mu = 10.0\nrho_c = inf"),
            "`rho_c` must be positive and finite",
        ),
        (
            "time-no-steps",
            &|t| format!("{t}\n[time]\nend = 1.0\n"),
            "[time]: no steps",
        ),
        (
            "time-bad-end",
            &|t| format!("{t}\n[time]\nend = -1.0\ndt = 0.1\n"),
            "`end` must be positive",
        ),
        (
            "time-bad-dt",
            &|t| format!("{t}\n[time]\nend = 1.0\ndt = 2.0\n"),
            "`dt` must be positive and at most `end`",
        ),
        (
            "time-bad-times",
            &|t| format!("{t}\n[time]\nend = 1.0\ntimes = [0.5, 0.2]\n"),
            "`times` must increase",
        ),
        (
            "time-bad-lambda",
            &|t| format!("{t}\n[time]\nend = 1.0\ndt = 0.5\nlambda = [[0.5, 0.0], [1.0, 1.0]]\n"),
            "`lambda` needs at least two",
        ),
        (
            "time-and-path",
            &|t| format!("{t}\n[steps]\npath = [0.0, 1.0]\n[time]\nend = 1.0\ndt = 0.5\n"),
            "with [time], give the load factor as [time] lambda",
        ),
    ];
    for (tag, edit, words) in cases {
        let (o, p) = case_with(tag, edit);
        let e = stderr(&o);
        let file = p.file_name().unwrap().to_str().unwrap();
        assert!(
            !o.status.success() && e.contains(words) && e.contains(&format!("{file}:")),
            "{tag}: {e}"
        );
        // refused before anything is solved
        assert!(
            !p.parent().unwrap().join("out/summary.json").exists(),
            "{tag}"
        );
    }
}

#[test]
fn conflicting_dirichlet_values_on_a_shared_node_are_refused() {
    // "bottom" and "left" share the origin; they disagree on ux there
    let (o, _) = case_with("conflict", |t| {
        t.to_string() + "\n[[bc]]\ngroup = \"bottom\"\nux = 0.1\n"
    });
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("share a node") && e.contains("different ux"),
        "{e}"
    );
}

#[test]
fn bad_geo_files_give_clear_errors() {
    let dir = scratch("bad-geo");
    let broken = dir.join("broken.geo");
    std::fs::write(&broken, "Point(1) = {0, 0, 0};\nLine(1) = {1, 2;\n").unwrap();
    let o = tmc(&["mesh", broken.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("gmsh failed on") && e.contains("broken.geo"),
        "{e}"
    );
    let untagged = dir.join("untagged.geo");
    std::fs::write(
        &untagged,
        "Point(1) = {0,0,0}; Point(2) = {1,0,0}; Point(3) = {1,1,0};\nLine(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,1};\nCurve Loop(1) = {1,2,3}; Plane Surface(1) = {1};\n",
    )
    .unwrap();
    let o = tmc(&["mesh", untagged.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("no physical groups"),
        "{e}"
    );
    assert!(!dir.join("untagged.msh").exists(), "nothing half-written");
    let o = tmc(&["mesh", "geo/no-such.geo"]);
    assert!(!o.status.success() && stderr(&o).contains("no such .geo file"));
}

#[test]
fn a_load_beyond_reach_fails_clearly_and_keeps_converged_steps() {
    // squeeze the slab to nothing: J → 0 cannot be reached
    let (o, p) = case_with("crush", |t| {
        t.replace("ux = 0.2", "ux = -2.0") + "\n[steps]\ninitial = 0.25\nmin = 0.01\nmax = 0.5\n"
    });
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("below the minimum step") && e.contains("converged steps up to"),
        "{e}"
    );
    let out = p.parent().unwrap().join("out");
    let s = summary(&out);
    assert_eq!(s["converged"], false);
    let steps = s["load_steps"].as_u64().unwrap() as usize;
    assert!(steps >= 1);
    let (cols, rows) = history(&out);
    assert_eq!(rows.len(), steps + 1);
    let j = cols.iter().position(|c| c == "min_J_solid").unwrap();
    assert!(
        rows.iter().all(|r| r[j] > 0.0),
        "no accepted step has J ≤ 0"
    );
    assert!(out.join(format!("step_{steps:04}.vtu")).is_file());
}

#[test]
fn meshio_reads_the_vtu_files() {
    let (s, dir) = solve_case("slab-stretch");
    let vtu = dir.join(format!("step_{:04}.vtu", s.load_steps));
    let o = Command::new("/usr/bin/python3")
        .args(["-c", "import sys, meshio; m = meshio.read(sys.argv[1]); print(len(m.points), m.cells[0].type, sorted(m.point_data), sorted(m.cell_data))"])
        .arg(&vtu)
        .output()
        .expect("python3-meshio is installed by make test");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.starts_with("45 quad") && out.contains("'u'") && out.contains("'sigma'"),
        "{out}"
    );
}

/// Regression: `.geo` parameters set for one meshing run leaked into the next one in the same
/// process (gmsh keeps its parser symbols across sessions, and `DefineConstant` keeps a
/// symbol that exists), so a later mesh of another scene came out with the wrong density.
#[test]
fn geo_parameters_do_not_leak_into_the_next_mesh() {
    use tmc::mesh::gmsh::{MeshOptions, mesh_geo};
    use tmc::mesh::msh::read_msh;
    let dir = scratch("geo-param-leak");
    let geo = root().join("geo/slab.geo");
    let cells = |params: &[(&str, f64)], name: &str| {
        let out = dir.join(name);
        mesh_geo(
            &geo,
            &out,
            &MeshOptions {
                order: 1,
                set_numbers: params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
                ..Default::default()
            },
        )
        .unwrap();
        read_msh(&out).unwrap().n_cells()
    };
    assert_eq!(cells(&[("n", 2.0), ("m", 1.0)], "a.msh"), 2);
    assert_eq!(cells(&[], "b.msh"), 8 * 4, "defaults of slab.geo");
}

/// Quadratic cells are written in VTK's node order: meshio, which maps gmsh's order to VTK's
/// on its own, reads the same cells (as sequences of node positions) from the `.msh` as from
/// tmc's `.vtu`, and as from the two parts a run on two ranks writes.
#[test]
fn quadratic_cells_reach_vtk_in_vtk_order() {
    use tmc::mesh::gmsh::{MeshOptions, mesh_geo};
    use tmc::mesh::msh::read_msh;
    use tmc::output::nodal::NodalFields;
    use tmc::output::vtu::Piece;
    use tmc::output::{StepFields, write_vtu};
    let dir = scratch("vtk-order");
    for (geo, incomplete) in [
        ("bar3d.geo", false),
        ("bar3d.geo", true),
        ("box-tet.geo", false),
        ("mixed2d.geo", false),
        ("mixed2d.geo", true),
    ] {
        let tag = format!("{}-{incomplete}", geo.trim_end_matches(".geo"));
        let msh = dir.join(format!("{tag}.msh"));
        let opts = MeshOptions {
            order: 2,
            incomplete,
            ..Default::default()
        };
        mesh_geo(&root().join("geo").join(geo), &msh, &opts).unwrap();
        let mesh = read_msh(&msh).unwrap();
        let n = mesh.coords.len();
        let cells = vec![Default::default(); mesh.n_cells()];
        let ints = vec![0; mesh.n_cells()];
        let vtu = dir.join(format!("{tag}.vtu"));
        let u = vec![[0.0; 3]; n];
        let nodal = NodalFields {
            sigma: vec![[[0.0; 3]; 3]; n],
            q: vec![[0.0; 3]; n],
        };
        let fields = StepFields {
            u: &u,
            theta: None,
            p: None,
            cells: &cells,
            nodal: &nodal,
            region: &ints,
            kind: &ints,
            region_names: &["all".into()],
            friction: None,
            contact: None,
        };
        // the cells cut in two parts, every third to the second
        let second: Vec<bool> = (0..mesh.n_cells()).map(|c| c % 3 == 0).collect();
        let first: Vec<bool> = second.iter().map(|s| !s).collect();
        let parts = [&first, &second].map(|mine| Piece::part(&mesh, mine));
        let part_files = [0, 1].map(|k| dir.join(format!("{tag}_{k}.vtu")));
        // uncompressed and compressed, both read by meshio
        for level in [0, 1] {
            write_vtu(&vtu, &mesh, &fields, &Piece::whole(&mesh), level).unwrap();
            for (piece, file) in parts.iter().zip(&part_files) {
                write_vtu(file, &mesh, &fields, piece, level).unwrap();
            }
            let script = "import sys, meshio, numpy as np
def cells(m, dim):
    out = {}
    for b in m.cells:
        if b.dim != dim: continue
        out.setdefault(b.type, []).extend(
            tuple(map(tuple, np.round(m.points[c], 9))) for c in b.data)
    return out
def merged(ms, dim):
    out = {}
    for m in ms:
        for k, v in cells(m, dim).items():
            out.setdefault(k, []).extend(v)
    return {k: sorted(v) for k, v in out.items()}
dim = int(sys.argv[1])
ca = merged([meshio.read(sys.argv[2])], dim)
cb = merged([meshio.read(f) for f in sys.argv[3:]], dim)
print(sorted(ca), sorted(cb), 'same' if ca == cb else 'DIFFERENT')";
            for written in [&[vtu.clone()][..], &part_files[..]] {
                let o = Command::new("/usr/bin/python3")
                    .args(["-c", script])
                    .arg(mesh.dim.to_string())
                    .arg(&msh)
                    .args(written)
                    .output()
                    .unwrap();
                let out = String::from_utf8_lossy(&o.stdout);
                assert!(o.status.success(), "{}", stderr(&o));
                assert!(
                    out.trim_end().ends_with("same"),
                    "{tag}, zlib {level}, {} file(s): {out}",
                    written.len()
                );
            }
        }
    }
}

#[test]
fn bad_load_paths_are_refused_with_the_line() {
    // a group's path must have one value per value of [steps] path
    let (o, p) = case_with("path-length", |t| {
        t.replace("ux = 0.2\n", "ux = 0.2\npath = [0.0, 1.0]\n")
            + "[steps]\npath = [0.0, 1.0, 0.5]\n"
    });
    assert!(!o.status.success());
    let e = stderr(&o);
    let text = std::fs::read_to_string(&p).unwrap();
    let line = 1 + text.lines().position(|l| l == "path = [0.0, 1.0]").unwrap();
    assert!(
        e.contains(&format!("{}:{line}:", p.display())) && e.contains("3 finite values"),
        "{e}"
    );
    // the load path starts unloaded
    let (o, _) = case_with("path-start", |t| {
        t.to_string() + "[steps]\npath = [0.5, 1.0]\n"
    });
    assert!(!o.status.success());
    assert!(stderr(&o).contains("the first 0"), "{}", stderr(&o));
}

#[test]
fn a_load_path_ends_where_it_says_and_the_work_matches_the_energy() {
    // stretch to 0.2, back to 0.1: every path value is a step, the state at the end is the
    // state at λ = 0.5 of a monotonic run (hyperelastic), and ∫ f·du = stored energy
    let (o, p) = case_with("path-ok", |t| {
        t.to_string() + "[steps]\ninitial = 0.05\nmax = 0.05\npath = [0.0, 1.0, 0.5]\n"
    });
    assert!(o.status.success(), "{}", stderr(&o));
    let out = p.parent().unwrap().join("out");
    let s = summary(&out);
    assert_eq!(s["time"], 2.0);
    assert_eq!(s["lambda"], 0.5);
    let (w, e) = (
        s["external_work"].as_f64().unwrap(),
        s["energy"].as_f64().unwrap(),
    );
    assert!(e > 0.0 && (w - e).abs() < 1e-3 * e, "work {w} energy {e}");
    let (cols, rows) = common::history(&out);
    let c = cols.iter().position(|c| c == "time").unwrap();
    let times: Vec<f64> = rows.iter().map(|r| r[c]).collect();
    assert!(
        times.contains(&1.0) && times.last() == Some(&2.0),
        "{times:?}"
    );
}

fn is_png(p: &Path) -> bool {
    std::fs::read(p).is_ok_and(|b| b.len() > 1000 && b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

#[test]
fn a_tiny_study_writes_its_csv_table_and_plots() {
    let dir = scratch("study-tiny");
    let study = dir.join("tiny.toml");
    // the case by a path relative to the study's folder
    let up = "../".repeat(dir.strip_prefix(root()).unwrap().components().count());
    std::fs::write(
        &study,
        r#"description = "two meshes of the block"
case = "UP/cases/block.toml"
measure = ["gap", "Q_top"]
reference = "last"
history = ["gap"]

[[variant]]
name = "coarse"
set = { mesh_options = { params = { n = 4, m = 4, l = 1 } } }

[[variant]]
name = "fine"
set = { "mesh_options.params" = { n = 16, m = 8, l = 4 }, "region.medium.gamma" = 1e-4 }
paper = { gap = 6.3e-4 }
"#
        .replace("UP/", &up),
    )
    .unwrap();
    let out = dir.join("out");
    // run from the study's folder with relative paths, as `make studies` does from the root
    let o = Command::new(env!("CARGO_BIN_EXE_tmc"))
        .current_dir(&dir)
        .args(["study", "tiny.toml", "-o", "out", "-q"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    let head: Vec<&str> = lines[0].split(',').collect();
    for c in [
        "variant",
        "dofs",
        "load_steps",
        "newton_iterations",
        "assembly_s",
        "solver_s",
        "total_s",
        "peak_memory_mb",
        "gap",
        "Q_top",
        "err_gap",
        "error",
        "converged",
    ] {
        assert!(head.contains(&c), "no column {c}: {head:?}");
    }
    let field = |row: &str, c: &str| -> String {
        let i = head.iter().position(|h| *h == c).unwrap();
        row.split(',').nth(i).unwrap().to_string()
    };
    let (coarse, fine) = (lines[1], lines[2]);
    assert!(
        field(coarse, "dofs").parse::<f64>().unwrap() < field(fine, "dofs").parse::<f64>().unwrap()
    );
    // the reference (the last variant) has no error; the coarse mesh has some
    assert_eq!(field(fine, "error").parse::<f64>().unwrap(), 0.0);
    let e = field(coarse, "error").parse::<f64>().unwrap();
    assert!(e > 0.0 && e < 0.5, "coarse error {e}");
    assert_eq!(field(coarse, "converged"), "true");
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(
        md.contains("| coarse |") && md.contains("gap 0.00063") && md.contains("\"fine\""),
        "{md}"
    );
    for png in ["error_vs_time.png", "history_gap.png"] {
        assert!(is_png(&out.join(png)), "{png}");
    }
    // each variant's case is kept beside its results
    let case = std::fs::read_to_string(out.join("runs/fine/case.toml")).unwrap();
    assert!(
        case.contains("n = 16") && case.contains("block.geo"),
        "{case}"
    );
}

#[test]
fn a_study_naming_a_missing_group_is_refused_before_solving() {
    let dir = scratch("study-bad");
    let study = dir.join("bad.toml");
    std::fs::write(
        &study,
        format!(
            "case = \"{}\"\nmeasure = [\"gap\"]\nreference = \"last\"\n[[variant]]\nname = \"a\"\nset = {{ \"region.gas.gamma\" = 1e-3 }}\n",
            root().join("cases/block.toml").display()
        ),
    )
    .unwrap();
    let o = tmc(&[
        "study",
        study.to_str().unwrap(),
        "-o",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("bad.toml") && e.contains("variant \"a\"") && e.contains("gas"),
        "{e}"
    );
    assert!(!dir.join("out/runs/a").exists(), "nothing ran");
}

#[test]
fn plot_draws_history_columns() {
    let (o, p) = case_with("plot", |t| t.to_string());
    assert!(o.status.success());
    let out = p.parent().unwrap().join("out");
    let o = tmc(&["plot", out.to_str().unwrap(), "-c", "R_right_x,energy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_png(&out.join("R_right_x.png")) && is_png(&out.join("energy.png")));
    let o = tmc(&["plot", out.to_str().unwrap(), "-c", "nope"]);
    assert!(!o.status.success() && stderr(&o).contains("no column \"nope\""));
}

#[test]
fn plot_refuses_a_column_no_axis_holds_and_draws_huge_ones_that_fit() {
    // ±1e308 (or 1e-300 to 1.7e308) looped for ever in plotters' ticks; ±1e300 draws
    let dir = scratch("plot-huge");
    std::fs::create_dir_all(&dir).unwrap();
    for (values, drawn) in [
        (["1e308", "-1e308"], false),
        (["1e-300", "1.7e308"], false),
        (["1e300", "-1e300"], true),
    ] {
        std::fs::write(
            dir.join("history.csv"),
            format!(
                "step,lambda,energy\n0,0,0\n1,0.5,{}\n2,1,{}\n",
                values[0], values[1]
            ),
        )
        .unwrap();
        let png = dir.join("energy.png");
        let _ = std::fs::remove_file(&png);
        let o = tmc(&["plot", dir.to_str().unwrap(), "-c", "energy"]);
        assert_eq!(o.status.success(), drawn, "{values:?}: {}", stderr(&o));
        assert_eq!(png.exists(), drawn, "{values:?}");
        if !drawn {
            assert!(
                stderr(&o).contains("span more than 1e307"),
                "{}",
                stderr(&o)
            );
        }
    }
}

/// The write end of a pipe whose read end is already closed: writing to it fails (EPIPE), as
/// writing into `| head` does once head has exited.
fn closed_pipe() -> std::process::Stdio {
    use std::os::fd::FromRawFd;
    let mut fds = [0; 2];
    // SAFETY: pipe fills two new descriptors; the read end is closed at once and the write
    // end is handed to the Stdio, which owns and closes it.
    unsafe {
        assert_eq!(libc::pipe(fds.as_mut_ptr()), 0);
        libc::close(fds[0]);
        std::process::Stdio::from_raw_fd(fds[1])
    }
}

#[test]
fn a_closed_pipe_silences_the_output_and_the_run_goes_on() {
    // `tmc check CASE | head` and `tmc solve CASE 2>&1 | head`: no panic, the exit code of the
    // command itself, and a solve writes all its results
    let case = root().join("cases/block-transient.toml");
    let out = scratch("closed-pipe").join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args(["check", case.to_str().unwrap()])
        .stdout(closed_pipe())
        .output()
        .unwrap();
    assert!(o.status.success(), "check: {}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    let status = Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args(["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .stdout(closed_pipe())
        .stderr(closed_pipe())
        .status()
        .unwrap();
    assert!(status.success(), "solve: {status}");
    let s = summary(&out);
    assert_eq!(s["converged"], true);
    let steps = s["load_steps"].as_u64().unwrap();
    assert!(steps > 1, "{steps} steps");
    assert!(out.join(format!("step_{steps:04}.vtu")).is_file());
}

/// `tmc check` of cases/block.toml with the replacements `edits` made in its text and one more
/// `[[bc]]` on "medium_left" (which shares the node at the origin with "bottom") holding
/// `left`.
fn check_shared_node(tag: &str, edits: &[(&str, &str)], left: &str) -> Output {
    let mut text = shipped_case("block");
    for (from, to) in edits {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    let p = write_case(
        tag,
        &format!("{text}\n[[bc]]\ngroup = \"medium_left\"\n{left}\n"),
    );
    tmc(&["check", p.to_str().unwrap()])
}

#[test]
fn shared_nodes_conflict_only_where_their_values_differ_on_the_load_path() {
    let held = [("uy = 0.0\n", "uy = 0.0\nramp = false\n")];
    // "bottom" holds ux = 0 from the start, "medium_left" ramps ux = 0: the same value all
    // along, accepted
    let o = check_shared_node("conflict-held-ramped", &held, "ux = 0.0");
    assert!(o.status.success(), "{}", stderr(&o));
    // held 0 and ramped 0.1 agree at λ = 0 and part at λ = 1, by 0.1: refused, saying where
    let o = check_shared_node("conflict-differ", &held, "ux = 0.1");
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(
        e.contains("\"bottom\" and \"medium_left\" share a node at [0.0, 0.0, 0.0]")
            && e.contains("ux: 0 and 0.1 at t = 1 (λ = 1), 0.1 apart"),
        "{e}"
    );
    // θ on paths of their own (from the initial 0): 10 × [0, 2] on "bottom" and 40 × [0, 0.5]
    // on "medium_left" are 0 and then 20 alike, accepted; 40 × [0, 1] parts at t = 1
    let paths = [(
        "theta = 20.0\nramp = false",
        "theta = 10.0\npath = [0.0, 2.0]",
    )];
    let o = check_shared_node(
        "conflict-paths-agree",
        &paths,
        "theta = 40.0\npath = [0.0, 0.5]",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = check_shared_node(
        "conflict-paths-part",
        &paths,
        "theta = 40.0\npath = [0.0, 1.0]",
    );
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("theta: 20 and 40 at t = 1 (λ = 1), 20 apart"),
        "{e}"
    );
}

#[test]
fn set_reaches_every_entry_of_a_group_with_two() {
    // cases/slab-conduction.toml with two heat-flux [[bc]] on "top" (the second named): --set
    // by number (from 1, file order) or by name reaches either; the group alone is refused with
    // both entries and their lines; a flux on either entry heats the slab alike
    let text = shipped_case("slab-conduction")
        + "\n[[bc]]\ngroup = \"top\"\nheat_flux = 0.0\n\n[[bc]]\ngroup = \"top\"\nname = \"lid\"\nheat_flux = 0.0\n";
    let case = write_case("set-two-entries", &text);
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "[[bc]]")
        .map(|(n, _)| n + 1)
        .collect();
    let theta_mid = |set: &str| -> Result<f64, String> {
        let out = case
            .parent()
            .unwrap()
            .join(format!("out-{}", set.replace(['#', '='], "_")));
        let o = solve_cli(&case, &out, &["--set", set]);
        if o.status.success() {
            Ok(summary(&out)["probes"]["theta_mid"].as_f64().unwrap())
        } else {
            Err(stderr(&o))
        }
    };
    let none = theta_mid("bc.top#1.heat_flux=0.0").unwrap();
    let by_number = theta_mid("bc.top#2.heat_flux=50.0").unwrap();
    let by_name = theta_mid("bc.lid.heat_flux=50.0").unwrap();
    let on_first = theta_mid("bc.top#1.heat_flux=50.0").unwrap();
    println!("θ_mid: {none} without flux, {by_number} #2, {by_name} by name, {on_first} #1");
    assert!(by_number > none + 1.0, "the flux heats the slab");
    assert_eq!(by_number, by_name);
    assert!((on_first - by_number).abs() < 1e-9 * by_number);
    let e = theta_mid("bc.top.heat_flux=50.0").unwrap_err();
    let listed = format!(
        "bc.top#1 (line {}), bc.top#2 (line {})",
        lines[lines.len() - 2],
        lines[lines.len() - 1]
    );
    assert!(
        e.contains("2 [[bc]] have group or name \"top\"") && e.contains(&listed),
        "{e}"
    );
    let e = theta_mid("bc.top#3.heat_flux=50.0").unwrap_err();
    assert!(e.contains("there is no #3"), "{e}");
}

/// Run by `make test` on a build without the `petsc` feature (its own target folder).
#[cfg(not(feature = "petsc"))]
#[test]
fn without_petsc_the_engine_and_mpirun_say_how_to_build_it() {
    let case = root().join("cases/block.toml");
    let out = scratch("without-petsc");
    let o = tmc(&[
        "solve",
        case.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "solver.engine=\"petsc\"",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("engine = \"petsc\"") && e.contains("cargo build --release --features petsc"),
        "{e}"
    );
    assert!(!out.join("summary.json").exists(), "nothing solved");
    // under mpirun: every rank ends with the same words, no MPI abort
    let o = mpirun_tmc(
        2,
        &[
            "solve".as_ref(),
            case.as_os_str(),
            "-q".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("mpirun -n 2") && e.contains("--features petsc"),
        "{e}"
    );
    assert!(!e.contains("MPI_ERR"), "{e}");
    // faer's factors over the memory budget, and no PETSc to take over: faer, with a warning
    let o = tmc(&["check", case.to_str().unwrap(), "--memory", "1"]);
    let report = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(o.status.success(), "{report}");
    assert!(
        report.contains("warning: engine \"auto\": a run on faer would take about")
            && report.contains("more than the 1 MB it has")
            && report.contains("--features petsc")
            && report.contains("linear solver: mechanics: faer"),
        "{report}"
    );
}

/// `tmc check CASE` under `taskset -c CPUS` (on the first CPUs), with `vars` set; its output.
fn check_on_cpus(cpus: &str, vars: &[(&str, &str)]) -> String {
    let out = Command::new("taskset")
        .args([
            "-c",
            cpus,
            env!("CARGO_BIN_EXE_tmc"),
            "check",
            "cases/block.toml",
        ])
        .env_remove("RAYON_NUM_THREADS")
        .envs(vars.iter().copied())
        .current_dir(root())
        .output()
        .expect("taskset (util-linux) runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn the_thread_count_comes_from_the_cpus_a_process_may_use_and_is_passed_to_rayon_as_read() {
    // one CPU allowed: one thread, whatever the machine has
    let one = check_on_cpus("0", &[]);
    assert!(
        one.contains("threads: 1 per process (one per CPU this process may use"),
        "{one}"
    );
    // a count with spaces around it is that count, and rayon runs it (rayon alone would fall
    // back to every CPU)
    let three = check_on_cpus("0", &[("RAYON_NUM_THREADS", " 3 ")]);
    assert!(
        three.contains("threads: 3 per process (RAYON_NUM_THREADS)"),
        "{three}"
    );
    // 0: the default
    let zero = check_on_cpus("0", &[("RAYON_NUM_THREADS", "0")]);
    assert!(
        zero.contains("threads: 1 per process (one per CPU"),
        "{zero}"
    );
}

/// `tmc solve cases/block-plate-3d-tm1.toml` (Table 2's 8×8 row: a coupled 3D scene whose
/// factors are worked over their elimination tree) on `threads` threads into `out`; its
/// history as rows of fields, the header first.
fn history_on_threads(threads: &str, out: &Path) -> Vec<Vec<String>> {
    let o = Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args(["solve", "cases/block-plate-3d-tm1.toml", "-o"])
        .arg(out)
        .env("RAYON_NUM_THREADS", threads)
        .current_dir(root())
        .output()
        .expect("tmc runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    text.lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn a_3d_run_gives_the_same_answers_at_one_and_two_threads_and_the_same_history_twice() {
    let dir = scratch("threads");
    let one = history_on_threads("1", &dir.join("one"));
    let two = history_on_threads("2", &dir.join("two"));
    let again = history_on_threads("2", &dir.join("again"));
    let head = &one[0];
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    // twice on two threads: the same history, every column but the clock's
    let wall = col("wall_seconds");
    let strip = |h: &[Vec<String>]| -> Vec<Vec<String>> {
        h.iter()
            .map(|r| {
                (r.iter().enumerate().filter(|(c, _)| *c != wall))
                    .map(|(_, v)| v.clone())
                    .collect()
            })
            .collect()
    };
    assert_eq!(strip(&two), strip(&again), "two runs on two threads differ");
    // one thread against two: the same steps and Newton iterations, the gap and every
    // reaction and heat flow to 1e-10 of the column's largest
    assert_eq!(one.len(), two.len(), "load steps differ with the threads");
    assert!(one.len() > 5, "{} rows", one.len());
    let its = col("newton_iterations");
    for (a, b) in one.iter().zip(&two).skip(1) {
        assert_eq!(a[its], b[its], "Newton iterations differ at step {}", a[0]);
    }
    let answers: Vec<usize> = (0..head.len())
        .filter(|&c| head[c] == "gap" || head[c].starts_with("R_") || head[c].starts_with("Q_"))
        .collect();
    assert!(answers.len() >= 5, "{head:?}");
    for c in answers {
        let value = |r: &Vec<String>| r[c].parse::<f64>().unwrap();
        let largest = (one.iter().skip(1))
            .map(|r| value(r).abs())
            .fold(0.0, f64::max);
        for (a, b) in one.iter().zip(&two).skip(1) {
            let (x, y) = (value(a), value(b));
            assert!(
                (x - y).abs() <= 1e-10 * largest,
                "{} at step {}: {x} on one thread, {y} on two",
                head[c],
                a[0]
            );
        }
    }
}

/// A `.geo` meshed before with the same parameters is taken from the cache of meshes: gmsh is
/// not opened, `tmc mesh` says so, and the mesh is the one made the first time. Other
/// parameters, or the cache turned off, mesh it again.
#[test]
fn a_mesh_made_before_is_taken_from_the_cache_without_gmsh() {
    let dir = scratch("mesh-cache");
    let cache = dir.join("cache");
    let env = [
        ("LD_DEBUG", "files"),
        ("TMC_MESH_CACHE", cache.to_str().unwrap()),
    ];
    let opened = |o: &Output| {
        assert!(o.status.success(), "{}", stderr(o));
        stderr(o)
            .lines()
            .any(|l| l.contains("file=") && l.contains("libgmsh"))
    };
    let said = |o: &Output| String::from_utf8_lossy(&o.stdout).contains("as meshed before");
    let mesh = |name: &str, extra: &[&str], env: &[(&str, &str)]| {
        let msh = dir.join(name);
        let mut args = vec!["mesh", "geo/block.geo", "-o", msh.to_str().unwrap()];
        args.extend(extra);
        let o = tmc_with(&args, env);
        (o, std::fs::read(&msh).unwrap_or_default())
    };
    let n = ["--set", "n=6"];
    let (o, first) = mesh("first.msh", &n, &env);
    assert!(opened(&o) && !said(&o), "meshed the first time");
    let (o, again) = mesh("again.msh", &n, &env);
    assert!(
        !opened(&o) && said(&o),
        "taken from the cache: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(!first.is_empty() && again == first, "the same mesh");
    let (o, _) = mesh("other.msh", &["--set", "n=8"], &env);
    assert!(opened(&o), "other parameters: meshed");
    let (o, off) = mesh("off.msh", &n, &[env[0], ("TMC_MESH_CACHE", "off")]);
    assert!(opened(&o) && !said(&o), "the cache off: meshed");
    assert_eq!(off, first, "gmsh makes the same mesh again");
    // a run meshes its case's .geo (the shipped block's own parameters) once, not again
    let case = dir.join("block.toml");
    std::fs::write(&case, shipped_case("block")).unwrap();
    let out = dir.join("out");
    let o = tmc_with(&solve_args(&case, &out), &env);
    assert!(
        opened(&o),
        "the shipped case's own parameters, the first time"
    );
    let o = tmc_with(&solve_args(&case, &out), &env);
    assert!(!opened(&o), "and not again");
    assert_eq!(summary(&out)["converged"], true);
}

/// gmsh (with OpenCASCADE) and PETSc are opened when a run needs them, not when tmc starts:
/// linked, their libraries cost every start a quarter of a second of symbol lookups.
#[test]
fn gmsh_is_loaded_only_to_mesh_and_petsc_only_for_its_engine() {
    let dir = scratch("loaded-when-needed");
    let loaded = |o: &Output, lib: &str| {
        // glibc's loader names each library it opens under LD_DEBUG=files, by path or name
        stderr(o)
            .lines()
            .any(|l| l.contains("file=") && l.contains(lib))
    };
    // meshed each time: a mesh kept from before would open no gmsh (the test above)
    let debug = [("LD_DEBUG", "files"), ("TMC_MESH_CACHE", "off")];
    let o = tmc_with(&["--version"], &debug);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(loaded(&o, "libmpi"), "LD_DEBUG names what is loaded");
    assert!(!loaded(&o, "libgmsh"), "{}", stderr(&o));
    assert!(!loaded(&o, "libpetsc"), "{}", stderr(&o));
    let msh = dir.join("plate-hole.msh");
    let msh_arg = msh.to_str().unwrap();
    let o = tmc_with(&["mesh", "geo/plate-hole.geo", "-o", msh_arg], &debug);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(loaded(&o, "libgmsh"), "meshing loads gmsh");
    assert!(!loaded(&o, "libpetsc"));
    let case = dir.join("plate-hole.toml");
    let geo = root().join("geo/plate-hole.geo");
    let text = shipped_case("plate-hole").replace(
        &format!("mesh = {:?}", geo.to_str().unwrap()),
        &format!("mesh = {msh_arg:?}"),
    );
    assert!(text.contains(msh_arg));
    std::fs::write(&case, text).unwrap();
    let out = dir.join("out");
    let o = tmc_with(&solve_args(&case, &out), &debug);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!loaded(&o, "libgmsh"), "a run on a .msh meshes nothing");
    assert!(!loaded(&o, "libpetsc"), "a run with faer needs no PETSc");
    assert_eq!(summary(&out)["converged"], true);
    if cfg!(feature = "petsc") {
        let mut args = solve_args(&case, &out);
        args.extend(["--set", "solver.engine=\"petsc\""]);
        let o = tmc_with(&args, &debug);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(loaded(&o, "libpetsc"), "the PETSc engine loads PETSc");
        assert!(!loaded(&o, "libgmsh"));
        assert_eq!(summary(&out)["engine"], "petsc");
    }
}
