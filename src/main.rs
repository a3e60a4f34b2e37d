//! The `tmc` command: a thin layer over the library.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use tmc::driver::{SolveOptions, run};
use tmc::mesh::gmsh::{MeshOptions, mesh_geo};
use tmc::solver::idle::IdleThreads;
use tmc::{note, say};

#[derive(Parser)]
#[command(
    name = "tmc",
    version,
    about = "Thermo-mechanical contact with the third-medium method"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh a gmsh .geo file into MSH 4.1.
    Mesh {
        /// The .geo file.
        geo: PathBuf,
        /// Output .msh (default: next to the .geo).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Element order.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=2))]
        order: u8,
        /// Serendipity second-order elements (quad8, hex20).
        #[arg(long)]
        incomplete: bool,
        /// Set a .geo parameter: --set NAME=VALUE (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_param)]
        set: Vec<(String, f64)>,
        /// Show gmsh's log.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Solve a case file.
    Solve {
        /// The case (.toml).
        case: PathBuf,
        /// Output folder (default: results/NAME).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// No progress bar, no summary line.
        #[arg(short, long)]
        quiet: bool,
        /// One line per load step: λ, Δλ, Newton iterations and the last residual of each
        /// field (u, θ, p), relative to its first.
        #[arg(short, long)]
        verbose: bool,
        /// Set a case key: --set KEY.PATH=VALUE, a dotted path as in a study's `set`
        /// (mesh_options.params.n=16, region.medium.gamma=1e-5, steps.max=0.2); repeatable.
        #[arg(long = "set", value_name = "KEY.PATH=VALUE", value_parser = parse_set)]
        set: Vec<(String, String)>,
        /// Continue the run in the output folder from its last converged step (its
        /// restart.json), exactly as if it had not stopped. The case may change only its
        /// [steps] controls (not `path`) and [output].
        #[arg(long)]
        restart: bool,
        /// What the other threads do while a linear solve runs on one: spin while the solve
        /// hands them work and then for at most this many milliseconds without, before they
        /// sleep; `spin` (through every solve: a core busy for the whole run, the fastest
        /// on a machine of your own); `sleep` (at once: frees the cores for others).
        #[arg(
            long,
            value_name = "MS|spin|sleep",
            env = IdleThreads::VAR,
            default_value_t = IdleThreads::default(),
            value_parser = IdleThreads::parse
        )]
        idle_threads: IdleThreads,
        /// The memory (MB) the linear algebra may take: with `[solver] engine = "auto"`, a
        /// run whose faer factors would need more solves on PETSc's multigrid (default: what
        /// the machine has available).
        #[arg(long, value_name = "MB", env = "TMC_MEMORY_MB", value_parser = parse_memory)]
        memory: Option<f64>,
    },
    /// Check a case as `solve` would up to its first step (mesh, groups, physics, strategy,
    /// unknowns, memory, threads, the initial state) and report; writes nothing where results
    /// go.
    Check {
        /// The case (.toml).
        case: PathBuf,
        /// Set a case key, as for `solve`.
        #[arg(long = "set", value_name = "KEY.PATH=VALUE", value_parser = parse_set)]
        set: Vec<(String, String)>,
        /// The memory (MB) the linear algebra may take, as for `solve`.
        #[arg(long, value_name = "MB", env = "TMC_MEMORY_MB", value_parser = parse_memory)]
        memory: Option<f64>,
    },
    /// Solve a scene over a list of variants: study.csv, study.md, error-vs-time and history
    /// plots.
    Study {
        /// The study (.toml).
        study: PathBuf,
        /// Output folder (default: results/NAME).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// No progress lines.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Draw history.csv columns of a solved case against λ (or the time), one PNG per column.
    Plot {
        /// The results folder of a solve (holds history.csv).
        results: PathBuf,
        /// Columns to draw (default: probes, reactions, energy, work).
        #[arg(short, long, value_delimiter = ',')]
        columns: Vec<String>,
        /// The x column (default: `time` where the case has a [time] section or λ holds while
        /// the pseudo-time runs on, as in a press then a slide; else `lambda`).
        #[arg(short, long)]
        x: Option<String>,
        /// Output folder (default: the results folder).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

fn parse_param(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got \"{s}\""))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("\"{v}\" is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{k} = {v} is not a finite number"));
    }
    Ok((k.trim().to_string(), v))
}

/// A memory budget in MB: a positive number.
fn parse_memory(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a positive number of MB, got {s:?}")),
    }
}

fn parse_set(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY.PATH=VALUE, got \"{s}\""))?;
    Ok((k.trim().to_string(), v.trim().to_string()))
}

fn print_chain(e: &dyn std::error::Error) {
    note!("error: {e}");
    let mut src = e.source();
    while let Some(s) = src {
        note!("  caused by: {s}");
        src = s.source();
    }
}

/// A run's error, printed by rank 0. On several ranks, a rank whose run failed while another
/// rank's goes on (a PETSc call that failed in its part alone, the others waiting for it in a
/// collective call) says so itself and ends every rank: otherwise the run would hang, silent.
fn report_failure(e: &dyn std::error::Error) {
    #[cfg(feature = "petsc")]
    {
        let ranks = tmc::parallel::Ranks::world();
        if !ranks.is_serial() && !tmc::parallel::petsc::all_failed(FAILURE_WAIT) {
            note!(
                "error on rank {} of {} alone, while the others wait for it:",
                ranks.rank,
                ranks.size
            );
            print_chain(e);
            note!("(ending every rank)");
            tmc::parallel::petsc::abort(1);
        }
    }
    if !silent() {
        print_chain(e);
    }
}

/// How long a failed rank waits for the others to fail as well before it ends the run: ranks
/// that fail together get here within the time rank 0 takes to write the failed run's
/// summary, far less than this (and its files are written whole or not at all).
#[cfg(feature = "petsc")]
const FAILURE_WAIT: std::time::Duration = std::time::Duration::from_secs(60);

fn main() -> ExitCode {
    let cli = Cli::parse();
    // before any other thread starts, so that all of them leave the signals to one thread
    tmc::driver::take_signals(matches!(cli.command, Command::Solve { .. }));
    // the ranks share the CPUs; a thread count this machine cannot start (a huge one would
    // hang while spawning) is refused before anything starts
    let ranks = tmc::parallel::launched_size().unwrap_or(1).max(1);
    let threads = match tmc::threads::decide(ranks) {
        Ok(threads) => threads,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(what) = serial_only(&cli.command) {
        // no MPI to start: every rank ends here, rank 0 says why
        if tmc::parallel::launched_rank().unwrap_or(0) == 0 {
            note!(
                "error: mpirun -n {}: tmc {what} runs on one process (only `tmc solve` and \
                 `tmc check` run on several ranks); run it without mpirun",
                tmc::parallel::launched_size().unwrap_or(0)
            );
        }
        return ExitCode::FAILURE;
    }
    if let Err(e) = start_ranks().and_then(|_| tmc::threads::start(threads).map(|_| ())) {
        note!("error: {e}");
        return ExitCode::FAILURE;
    }
    let code = command(cli);
    #[cfg(feature = "petsc")]
    tmc::parallel::petsc::finish();
    code
}

/// Under `mpirun -n N` (N > 1), the command if it cannot run on several ranks: a study starts
/// each variant as a process of its own (which would start MPI inside the job and fail), and
/// meshing or plotting on every rank would write the same files at once.
fn serial_only(command: &Command) -> Option<&'static str> {
    if tmc::parallel::launched_size().is_none_or(|n| n <= 1) {
        return None;
    }
    match command {
        Command::Study { .. } => Some("study"),
        Command::Plot { .. } => Some("plot"),
        Command::Mesh { .. } => Some("mesh"),
        _ => None,
    }
}

/// Under `mpirun -n N` (N > 1): MPI started (the ranks share the CPUs: `tmc::threads`),
/// progress and errors from rank 0 only.
fn start_ranks() -> Result<(), String> {
    let Some(_n) = tmc::parallel::launched_size().filter(|&n| n > 1) else {
        return Ok(());
    };
    #[cfg(not(feature = "petsc"))]
    return Err(format!("mpirun -n {_n}: {}", tmc::parallel::NOT_BUILT));
    #[cfg(feature = "petsc")]
    {
        let ranks = tmc::parallel::petsc::start_mpi();
        if !ranks.is_root() {
            SILENT.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(())
    }
}

/// Set on ranks other than 0: they print nothing (rank 0 speaks for the run).
static SILENT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn silent() -> bool {
    SILENT.load(std::sync::atomic::Ordering::Relaxed)
}

fn command(cli: Cli) -> ExitCode {
    match cli.command {
        Command::Study {
            study,
            output,
            quiet,
        } => study_command(&study, output, quiet),
        Command::Plot {
            results,
            columns,
            x,
            output,
        } => match tmc::plot::plot_results(&results, &columns, x.as_deref(), output.as_deref()) {
            Ok(files) => {
                for f in files {
                    say!("wrote {}", f.display());
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                print_chain(&e);
                ExitCode::FAILURE
            }
        },
        Command::Mesh {
            geo,
            output,
            order,
            incomplete,
            set,
            verbose,
        } => {
            let stem = || PathBuf::from(geo.file_stem().unwrap_or_default()).with_extension("msh");
            let out = match output {
                // -o DIR: the mesh goes into the folder, named after the .geo
                Some(dir) if dir.is_dir() => dir.join(stem()),
                Some(out) => out,
                None => geo.with_extension("msh"),
            };
            let opts = MeshOptions {
                order,
                incomplete,
                set_numbers: set,
                verbose,
            };
            match mesh_geo(&geo, &out, &opts) {
                Ok(r) => {
                    for w in r.warnings.iter().chain(&r.mesh.untouched_bodies()) {
                        note!("warning: {w}");
                    }
                    let before = match r.cached {
                        true => ", as meshed before (TMC_MESH_CACHE=off meshes it again)",
                        false => "",
                    };
                    say!("wrote {} ({}D){before}", r.output.display(), r.dim);
                    print_mesh(&r.mesh);
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    print_chain(&e);
                    ExitCode::FAILURE
                }
            }
        }
        Command::Solve {
            case,
            output,
            quiet,
            verbose,
            set,
            restart,
            idle_threads,
            memory,
        } => {
            let opts = SolveOptions {
                out_dir: output,
                quiet: quiet || silent(),
                verbose: verbose && !silent(),
                idle_threads,
                sets: set,
                restart,
                memory_mb: memory,
            };
            solve_command(&case, &opts)
        }
        Command::Check { case, set, memory } => check_command(&case, set, memory),
    }
}

/// What a mesh holds: nodes, cells per kind, and every physical group with its cells.
fn print_mesh(mesh: &tmc::mesh::Mesh) {
    let kinds: Vec<String> = mesh
        .cell_counts()
        .iter()
        .map(|(k, n)| format!("{n} {}", k.name()))
        .collect();
    say!(
        "  {} nodes, {} cells ({})",
        mesh.coords.len(),
        mesh.n_cells(),
        kinds.join(", ")
    );
    for (g, group) in mesh.groups.iter().enumerate() {
        let n: usize = mesh
            .cells
            .iter()
            .chain(&mesh.facets)
            .filter(|b| b.groups.contains(&g))
            .map(|b| b.n_cells())
            .sum();
        say!("  group \"{}\" ({}D): {n} elements", group.name, group.dim);
    }
}

/// `tmc check`: the report of everything before the first step.
fn check_command(
    case: &std::path::Path,
    sets: Vec<(String, String)>,
    memory_mb: Option<f64>,
) -> ExitCode {
    let opts = SolveOptions {
        sets,
        memory_mb,
        quiet: true,
        ..Default::default()
    };
    match tmc::driver::check(case, &opts) {
        // rank 0 speaks for every rank (each rank's own figures on lines of their own)
        Ok(_) if silent() => ExitCode::SUCCESS,
        Ok(r) => {
            say!("{}: ready to solve", case.display());
            say!("mesh {} ({}D)", r.mesh.source.display(), r.mesh.dim);
            print_mesh(&r.mesh);
            for w in &r.mesh.warnings {
                say!("  warning: {w}");
            }
            say!("{}", r.physics);
            for w in &r.warnings {
                say!("{w}");
            }
            for e in &r.expansion {
                say!("thermal expansion in {e}");
            }
            let unknowns: Vec<String> =
                r.unknowns.iter().map(|(f, n)| format!("{n} {f}")).collect();
            say!("unknowns: {} ({} free)", unknowns.join(", "), r.free);
            say!("linear solver: {}", r.linear.join("; "));
            if let Some(t) = tmc::threads::chosen() {
                let running = rayon::current_num_threads();
                say!("threads: {running} per process ({})", t.why);
            }
            if !r.predicted_speedup.is_empty() {
                let at = |f: fn(&tmc::solver::linear::Speedup) -> f64| {
                    let at: Vec<String> = (r.predicted_speedup.iter())
                        .map(|(p, s)| format!("{:.1}× at {p}", f(s)))
                        .collect();
                    at.join(", ")
                };
                say!(
                    "factorisation: its elimination tree bounds its speed-up at {} threads \
                     (multiply-adds only)",
                    at(|s| s.factor)
                );
                say!(
                    "solves: the tree bounds their speed-up at {} threads (entries read; \
                     the memory's bandwidth lowers it)",
                    at(|s| s.solve)
                );
            }
            if let Some(why) = &r.engine_note {
                say!("{why}");
            }
            match r.factor_entries {
                _ if !r.per_rank.is_empty() => {
                    let ranks = r.per_rank.len();
                    let total: usize = r.per_rank.iter().map(|p| p.0).sum();
                    let factor = if r.factor_entries.is_some() {
                        ""
                    } else {
                        " besides the factor (PETSc's, sized when it factorises)"
                    };
                    say!("tangent: {total} entries over {ranks} ranks; at the run's peak{factor}:");
                    for (rank, (entries, mb)) in r.per_rank.iter().enumerate() {
                        say!("  rank {rank}: {entries} tangent entries, about {mb:.0} MB");
                    }
                }
                Some(n) => say!(
                    "tangent: {} entries; factor: {n} entries; about {:.0} MB at the run's peak",
                    r.tangent_entries,
                    r.estimated_mb()
                ),
                // PETSc lays its factor out when it factorises: the tangent is all that is known
                None => say!(
                    "tangent: {} entries, about {:.0} MB at the run's peak besides the factor; the factor is PETSc's, sized when it factorises",
                    r.tangent_entries,
                    r.estimated_mb()
                ),
            }
            if !r.probes.is_empty() {
                say!("probes: {}", r.probes.join(", "));
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            if !silent() {
                print_chain(&e);
            }
            ExitCode::FAILURE
        }
    }
}

/// `tmc study`: every variant, then the tables and plots; fails if any variant failed.
fn study_command(study: &std::path::Path, output: Option<PathBuf>, quiet: bool) -> ExitCode {
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            note!("error: cannot find the tmc executable: {e}");
            return ExitCode::FAILURE;
        }
    };
    let opts = tmc::study::StudyOptions {
        out_dir: output,
        exe,
        quiet,
    };
    match tmc::study::run_study(study, &opts) {
        Ok(r) => {
            let failed = r.outcomes.iter().filter(|o| !o.converged).count();
            say!(
                "study {}: {} variants ({failed} failed); wrote {}",
                r.name,
                r.outcomes.len(),
                r.files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            // the report names the failures, and so does the end of the run (quiet or not):
            // each failed variant with its error; the exit status tells scripts
            if !silent() {
                for o in r.outcomes.iter().filter(|o| !o.converged) {
                    let message = o.message.trim_start_matches("error: ");
                    eprintln!("error: variant \"{}\" failed: {message}", o.variant.name);
                }
            }
            if failed == 0 {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            if !silent() {
                print_chain(&e);
            }
            ExitCode::FAILURE
        }
    }
}

/// `tmc solve`: one case, with a line of results unless `quiet`.
fn solve_command(case: &std::path::Path, opts: &SolveOptions) -> ExitCode {
    let quiet = opts.quiet;
    match run(case, opts) {
        Ok(s) => {
            if !quiet {
                let probes: Vec<String> = s
                    .probes
                    .iter()
                    .map(|(k, v)| format!("{k} = {v:.6e}"))
                    .collect();
                say!(
                    "{}: {} dofs, {} load steps, {} Newton iterations, {:.2} s{}{}",
                    s.case,
                    s.dofs["total"],
                    s.load_steps,
                    s.newton_iterations,
                    s.wall_seconds,
                    if probes.is_empty() { "" } else { "; " },
                    probes.join(", ")
                );
                say!("results in {}", s.output);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            report_failure(&e);
            ExitCode::FAILURE
        }
    }
}
