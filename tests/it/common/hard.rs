//! The stability suite's hard cases, shared by `tests/it/stability.rs` (which asserts on them) and
//! `benches/stability.rs` (which prints their table). Coarse meshes: the whole list solves in
//! well under a minute on two cores.

use std::path::{Path, PathBuf};
use tmc::driver::{SolveError, SolveOptions, Summary, run};
use tmc::solver::idle::IdleThreads;

/// One hard case: a scene from `geo/`, its mesh parameters and the case body.
pub struct Hard {
    pub name: String,
    /// What makes it hard.
    pub what: &'static str,
    pub geo: &'static str,
    pub params: &'static str,
    pub body: String,
    /// Relative tolerance of the energy balance (external work vs stored energy), where it
    /// holds: hyperelastic scenes without thermal strain. The work is summed by the
    /// trapezoidal rule, whose error falls as Δλ²; the cases that check it cap Δλ.
    pub energy_tol: Option<f64>,
}

fn cases_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// A shipped case's body, without its `mesh` key, its mesh parameters and comments (a hard
/// case gives its own).
pub fn body_of(name: &str) -> String {
    let text = std::fs::read_to_string(cases_dir().join(format!("{name}.toml"))).unwrap();
    let own = |l: &str| {
        ["mesh =", "#", "[mesh_options]", "params ="]
            .iter()
            .any(|k| l.starts_with(k))
    };
    text.lines()
        .filter(|l| !own(l))
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The block scene without its thermal conditions: pure mechanics (fast, hyperelastic).
fn block_mech(extra: &str) -> String {
    let mut b = String::new();
    b.push_str(
        "[[region]]\ngroup = \"solid\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0\n\
         [[region]]\ngroup = \"medium\"\nkind = \"medium\"\ngamma = GAMMA\nbeta1 = 1.0\nbeta2 = 1e-2\n\
         [[bc]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\n\
         [[probe]]\nname = \"gap\"\nfield = \"distance\"\nfrom = [1.0, 0.0]\nto = [1.0, 0.25]\naxis = \"y\"\n",
    );
    b.push_str(extra);
    b
}

/// Press the top 0.3 down, then (pseudo-time 1 to 2) slide it `ux` along x, Δλ ≤ 0.025.
fn press_and_slide(ux: f64) -> String {
    format!(
        "[[bc]]\ngroup = \"top\"\nuy = -0.3\npath = [0.0, 1.0, 1.0]\n\
         [[bc]]\ngroup = \"top\"\nux = {ux}\npath = [0.0, 0.0, 1.0]\n\
         [steps]\ninitial = 0.025\nmax = 0.025\npath = [0.0, 1.0, 1.0]\n"
    )
}

const PRESS: &str = "[[bc]]\ngroup = \"top\"\nux = 0.0\nuy = -0.4\n";
const FINE_STEPS: &str = "[steps]\ninitial = 0.05\nmax = 0.05\n";

/// The γ values of the sweep.
pub const GAMMAS: [f64; 5] = [1e-6, 1e-5, 1e-4, 1e-3, 1e-2];

pub fn all() -> Vec<Hard> {
    let coarse = "n = 16, m = 8, l = 4";
    let mut v = vec![
        Hard {
            name: "squeeze".into(),
            what: "medium squeezed to J < 1e-3 (block, top 0.4 down)",
            geo: "block.geo",
            params: coarse,
            body: block_mech(&format!("{PRESS}{FINE_STEPS}")).replace("GAMMA", "1e-4"),
            energy_tol: Some(0.01),
        },
        Hard {
            name: "sliding".into(),
            what: "press 0.3, then slide 0.6 (30 % of the width) along the interface",
            geo: "block.geo",
            params: coarse,
            body: block_mech(&press_and_slide(0.6)).replace("GAMMA", "1e-4"),
            energy_tol: Some(0.01),
        },
        Hard {
            name: "sliding-friction".into(),
            what: "press 0.3, then drag 0.15 with Coulomb friction μ = 0.3 in the medium",
            geo: "block.geo",
            params: coarse,
            body: block_mech(&press_and_slide(0.15))
                .replace("GAMMA", "1e-4")
                .replace(
                    "beta2 = 1e-2\n",
                    "beta2 = 1e-2\nfriction = { mu = 0.3, normal = [0, 1] }\n",
                ),
            // friction dissipates: the work exceeds the stored energy by what slid
            energy_tol: None,
        },
        Hard {
            name: "distorted".into(),
            what: "medium cells graded 1.15 per cell in opposite directions (slanted)",
            geo: "block.geo",
            params: "n = 16, m = 8, l = 4, skew = 1.15",
            body: block_mech(&format!("{PRESS}{FINE_STEPS}")).replace("GAMMA", "1e-4"),
            energy_tol: Some(0.01),
        },
        Hard {
            name: "very-coarse".into(),
            what: "4 x 1 medium cells under a 4 x 2 solid",
            geo: "block.geo",
            params: "n = 4, m = 2, l = 1",
            body: block_mech(&format!("{PRESS}{FINE_STEPS}")).replace("GAMMA", "1e-4"),
            energy_tol: Some(0.01),
        },
        Hard {
            name: "one-step".into(),
            what: "micro-contact's whole load asked for in one step: the controller cuts it",
            geo: "micro-contact.geo",
            params: "h = 0.1, np = 40, l = 3",
            body: body_of("micro-contact").replace(
                "path = [0.0, 0.25, 0.5, 1.0]",
                "path = [0.0, 1.0]\ninitial = 1.0\nmax = 1.0",
            ),
            energy_tol: None,
        },
        Hard {
            name: "unloading".into(),
            what: "load to λ = 1 and back to 0.2: the medium reopens, the heat flow drops",
            geo: "block.geo",
            params: coarse,
            body: body_of("block") + "[steps]\npath = [0.0, 0.2, 1.0, 0.2]\n",
            energy_tol: None,
        },
        Hard {
            name: "discs-ellipse".into(),
            what: "curved bodies wedged apart, two-way coupled (h = 0.12)",
            geo: "discs-ellipse.geo",
            params: "h = 0.12",
            body: body_of("discs-ellipse"),
            energy_tol: None,
        },
        Hard {
            name: "discs-ellipse-friction".into(),
            what: "the discs-ellipse with friction μ = 0.3, slip planes found by tmc (h = 0.12)",
            geo: "discs-ellipse.geo",
            params: "h = 0.12",
            body: body_of("discs-ellipse-friction"),
            energy_tol: None,
        },
        Hard {
            name: "friction-heating".into(),
            what: "a block dragged 0.2 in 0.5 s with friction μ = 0.3: the slip heats it",
            geo: "block.geo",
            params: coarse,
            body: body_of("friction-heating"),
            energy_tol: None,
        },
        Hard {
            name: "micro-contact".into(),
            what: "rough surfaces: no contact, two spots, full contact",
            geo: "micro-contact.geo",
            params: "h = 0.1, np = 40, l = 3",
            body: body_of("micro-contact"),
            energy_tol: None,
        },
        Hard {
            name: "sphere-block".into(),
            what: "3D tet4 indenter, curved contact (h = 0.15)",
            geo: "sphere-block.geo",
            params: "h = 0.15",
            body: body_of("sphere-block"),
            energy_tol: None,
        },
    ];
    for g in GAMMAS {
        v.push(Hard {
            name: format!("gamma-{g:.0e}"),
            what: "medium stiffness γ",
            geo: "block.geo",
            params: coarse,
            body: block_mech(&format!("{PRESS}{FINE_STEPS}")).replace("GAMMA", &format!("{g:e}")),
            energy_tol: Some(0.01),
        });
    }
    v
}

/// Solve a hard case into `dir` (the case file is written there too).
pub fn solve(h: &Hard, dir: &Path) -> Result<Summary, SolveError> {
    let mesh = format!(
        "mesh = \"{}\"\n[mesh_options]\nparams = {{ {} }}",
        cases_dir().join("../geo").join(h.geo).display(),
        h.params
    );
    solve_text(&mesh, h, dir, IdleThreads::Spin)
}

/// As [`solve`], on the mesh `msh` (a run's `mesh.msh`), with the pool's other threads doing
/// `idle` during linear solves. gmsh's unstructured meshers may give
/// another mesh of the same `.geo` in a process where other threads allocate meanwhile (they
/// order elements by address), so a solver's reproducibility is checked on one mesh.
#[allow(dead_code)] // the bench solves each case once
pub fn solve_on_mesh(
    h: &Hard,
    dir: &Path,
    msh: &Path,
    idle: IdleThreads,
) -> Result<Summary, SolveError> {
    solve_text(&format!("mesh = \"{}\"", msh.display()), h, dir, idle)
}

fn solve_text(
    mesh: &str,
    h: &Hard,
    dir: &Path,
    idle_threads: IdleThreads,
) -> Result<Summary, SolveError> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let text = format!("{mesh}\n{}", h.body);
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    run(
        &path,
        &SolveOptions {
            out_dir: Some(dir.join("out")),
            quiet: true,
            verbose: false,
            idle_threads,
            ..Default::default()
        },
    )
}
