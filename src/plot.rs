//! Line charts to PNG (plotters): history columns against λ (`tmc plot`) and the study plots.

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Bad { path: PathBuf, msg: String },
    #[error("cannot draw {path}: {msg}")]
    Draw { path: PathBuf, msg: String },
}

/// One named curve.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A chart: title, axis labels, curves, and which axes are logarithmic.
pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: &'a [Series],
    pub log_x: bool,
    pub log_y: bool,
}

/// The range of `v` with a margin; positive values only on a log axis. `None` when the values
/// span more than about 1e307 on a linear axis: no axis plotters draws holds them.
fn range(v: impl Iterator<Item = f64>, log: bool) -> Option<std::ops::Range<f64>> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for x in v.filter(|x| x.is_finite() && (!log || *x > 0.0)) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if !lo.is_finite() {
        return Some(if log { 0.1..10.0 } else { 0.0..1.0 });
    }
    if log {
        // whole decades, at least two (plotters puts its log ticks on the decades), within
        // what a double holds
        let (mut a, mut b) = ((lo.log10() - 0.005).floor(), (hi.log10() + 0.005).ceil());
        if b - a < 2.0 {
            a -= 1.0;
            b += 1.0;
        }
        Some(10f64.powf(a.max(-307.0))..10f64.powf(b.min(308.0)))
    } else {
        // plotters' ticks overflow (and loop) on spans near the largest double
        let span = hi - lo;
        if !(16.0 * span).is_finite() {
            return None;
        }
        let pad = if hi > lo {
            0.05 * span
        } else {
            0.5 * lo.abs().max(1.0)
        };
        let padded = (lo - pad)..(hi + pad);
        Some(if padded.start.is_finite() && padded.end.is_finite() {
            padded
        } else {
            lo..hi
        })
    }
}

/// Where the plots' font is looked for: `TMC_PLOT_FONT` if set, then DejaVu Sans where Debian
/// (`fonts-dejavu-core`), Fedora and Arch put it.
const FONT_FILES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Read the font once and give it to plotters as "sans-serif" (its `ab_glyph` renderer: the
/// `ttf` one, through font-kit, clips glyphs that reach left of their origin, such as the `J`
/// of `mJ`).
fn register_font(path: &Path) -> Result<(), PlotError> {
    static FONT: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    let registered = FONT.get_or_init(|| {
        let var = std::env::var_os("TMC_PLOT_FONT").map(PathBuf::from);
        let candidates: Vec<PathBuf> = var
            .into_iter()
            .chain(FONT_FILES.iter().map(PathBuf::from))
            .collect();
        let Some((file, bytes)) = candidates
            .iter()
            .find_map(|f| Some((f, std::fs::read(f).ok()?)))
        else {
            return Err(format!(
                "no font for the plots: install fonts-dejavu-core, or set TMC_PLOT_FONT to a \
                 .ttf file (looked for {})",
                FONT_FILES.join(", ")
            ));
        };
        // one font for the life of the process, as plotters wants it
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| format!("{} is not a font plotters can read", file.display()))
    });
    registered.clone().map_err(|msg| PlotError::Draw {
        path: path.to_owned(),
        msg,
    })
}

/// Draw `chart` into a PNG at `path`.
pub fn line_chart(path: &Path, chart: &Chart) -> Result<(), PlotError> {
    register_font(path)?;
    let axis = |label: &str, v: &mut dyn Iterator<Item = f64>, log: bool| {
        range(v, log).ok_or_else(|| PlotError::Draw {
            path: path.to_owned(),
            msg: format!("the values of {label} span more than 1e307: no axis can show them"),
        })
    };
    let xs = axis(
        chart.x_label,
        &mut chart
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0)),
        chart.log_x,
    )?;
    let ys = axis(
        chart.y_label,
        &mut chart
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1)),
        chart.log_y,
    )?;
    let spans = (xs.end - xs.start, ys.end - ys.start);
    let r = draw_then_rename(path, |p| match (chart.log_x, chart.log_y) {
        (false, false) => draw(p, chart, spans, xs, ys),
        (true, false) => draw(p, chart, spans, xs.log_scale(), ys),
        (false, true) => draw(p, chart, spans, xs, ys.log_scale()),
        (true, true) => draw(p, chart, spans, xs.log_scale(), ys.log_scale()),
    });
    r.map_err(|msg| PlotError::Draw {
        path: path.to_owned(),
        msg,
    })
}

/// Draw into a temporary PNG beside `path`, then rename: a failed draw (a full disk) leaves no
/// broken picture under the final name.
fn draw_then_rename(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let mut name = path.file_stem().unwrap_or_default().to_os_string();
    name.push(".part.png");
    let tmp = crate::files::TempFile::new(path.with_file_name(name));
    draw(tmp.path())?;
    tmp.sync()
        .and_then(|_| tmp.commit(path))
        .map_err(|e| e.to_string())
}

/// A tick label: as few digits as the axis needs, "0" for round-off around zero; on a log
/// axis only 1, 2 and 5 times a power of ten are labelled (the others would overlap).
pub fn tick_label(v: f64, span: f64, log: bool) -> String {
    if log {
        let m = v / 10f64.powf(v.log10().floor());
        if ![1.0, 2.0, 5.0].iter().any(|k| (m - k).abs() < 1e-6 * k) {
            return String::new();
        }
        return trim_sci(&format!("{v:.0e}"));
    }
    if v.abs() <= 1e-9 * span.abs().max(f64::MIN_POSITIVE) {
        return "0".into();
    }
    let big = v.abs().max(span.abs());
    if (1e-3..1e5).contains(&big) {
        let step = span.abs() / 10.0;
        let digits = (-step.log10()).ceil().clamp(0.0, 8.0) as usize;
        let t = format!("{v:.digits$}");
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    } else {
        trim_sci(&format!("{v:.2e}"))
    }
}

/// `2.50e-1` → `2.5e-1`, `1.00e3` → `1e3`.
fn trim_sci(s: &str) -> String {
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => s.to_string(),
    }
}

fn draw<X, Y>(
    path: &Path,
    chart: &Chart,
    (x_span, y_span): (f64, f64),
    x: X,
    y: Y,
) -> Result<(), String>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut c = ChartBuilder::on(&root)
        .caption(chart.title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x, y)
        .map_err(|x| e(&x))?;
    c.configure_mesh()
        .x_desc(chart.x_label)
        .y_desc(chart.y_label)
        .x_label_formatter(&|v| tick_label(*v, x_span, chart.log_x))
        .y_label_formatter(&|v| tick_label(*v, y_span, chart.log_y))
        .draw()
        .map_err(|x| e(&x))?;
    for (i, s) in chart.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(a, b)| {
                a.is_finite()
                    && b.is_finite()
                    && (!chart.log_x || *a > 0.0)
                    && (!chart.log_y || *b > 0.0)
            })
            .collect();
        c.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(s.name.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|x| e(&x))?;
    }
    // a legend only tells curves apart
    if chart.series.len() > 1 {
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// A history.csv: column names and rows.
pub struct History {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl History {
    /// Read a CSV of numbers under one header line (`NaN` for a quantity a scene lacks);
    /// every row must have the header's number of fields.
    pub fn read(path: &Path) -> Result<History, PlotError> {
        let bad = |msg: String| PlotError::Bad {
            path: path.to_owned(),
            msg,
        };
        let mut r = csv::ReaderBuilder::new()
            .has_headers(true)
            .from_path(path)
            .map_err(|e| match e.into_kind() {
                csv::ErrorKind::Io(source) => PlotError::Read {
                    path: path.to_owned(),
                    source,
                },
                other => bad(format!("{other:?}")),
            })?;
        let columns: Vec<String> = r
            .headers()
            .map_err(|e| bad(e.to_string()))?
            .iter()
            .map(String::from)
            .collect();
        if columns.is_empty() || columns == [""] {
            return Err(bad("empty file".into()));
        }
        let mut rows = Vec::new();
        for (i, record) in r.records().enumerate() {
            let record = record.map_err(|e| {
                bad(match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        pos: Some(pos),
                        expected_len,
                        len,
                    } => format!(
                        "line {}: {len} fields, but the header has {expected_len}",
                        pos.line()
                    ),
                    _ => e.to_string(),
                })
            })?;
            let row: Result<Vec<f64>, _> = record.iter().map(|v| v.trim().parse::<f64>()).collect();
            rows.push(row.map_err(|e| bad(format!("line {}: {e}", i + 2)))?);
        }
        Ok(History { columns, rows })
    }

    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[c]).collect())
    }
}

/// The columns `tmc plot` draws by default: probes, reactions, energy, work and heat (those
/// after the bookkeeping ones, and not the wall clock), skipping columns the scene does not
/// have (NaN) or that stay 0.
pub fn default_columns(h: &History) -> Vec<String> {
    use crate::driver::{HISTORY_SOLVER_COLUMNS, HISTORY_STEP_COLUMNS};
    let bookkeeping = |c: &str| {
        HISTORY_STEP_COLUMNS.contains(&c)
            || HISTORY_SOLVER_COLUMNS.contains(&c)
            || c == "wall_seconds"
    };
    h.columns
        .iter()
        .filter(|c| !bookkeeping(c))
        .filter(|c| {
            h.column(c)
                .is_some_and(|v| v.iter().any(|x| x.is_finite() && *x != 0.0))
        })
        .cloned()
        .collect()
}

/// `tmc plot`: one PNG per column of `results/NAME/history.csv` against `x` (default: the
/// physical time where the run has one, the pseudo-time where λ holds during it, else λ),
/// written to `out` (default the results folder). Returns the files written.
pub fn plot_results(
    dir: &Path,
    columns: &[String],
    x: Option<&str>,
    out: Option<&Path>,
) -> Result<Vec<PathBuf>, PlotError> {
    let path = dir.join("history.csv");
    let h = History::read(&path)?;
    let labels = Labels::read(dir);
    let x = x.unwrap_or(labels.default_x_of(&h));
    let bad = |msg: String| PlotError::Bad {
        path: path.clone(),
        msg,
    };
    let xs = h.column(x).ok_or_else(|| {
        bad(format!(
            "no column \"{x}\" (columns: {})",
            h.columns.join(", ")
        ))
    })?;
    let columns = if columns.is_empty() {
        default_columns(&h)
    } else {
        columns.to_vec()
    };
    if columns.is_empty() {
        return Err(bad(format!(
            "nothing to draw: every probe, reaction, energy and work column is zero or NaN; \
             name columns with -c (columns: {})",
            h.columns.join(", ")
        )));
    }
    // every column first: nothing is drawn if one is missing
    let mut curves = Vec::new();
    for c in &columns {
        let ys = h.column(c).ok_or_else(|| {
            bad(format!(
                "no column \"{c}\" (columns: {})",
                h.columns.join(", ")
            ))
        })?;
        curves.push((c, ys));
    }
    let out = out.unwrap_or(dir);
    std::fs::create_dir_all(out).map_err(|source| PlotError::Read {
        path: out.to_owned(),
        source,
    })?;
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut written = Vec::new();
    for (c, ys) in curves {
        let file = out.join(format!("{}.png", file_stem(c)));
        line_chart(
            &file,
            &Chart {
                title: &format!("{name}: {c}"),
                x_label: &labels.axis(x),
                y_label: &labels.axis(c),
                series: &[Series {
                    name: c.clone(),
                    points: xs.iter().copied().zip(ys).collect(),
                }],
                log_x: false,
                log_y: false,
            },
        )?;
        written.push(file);
    }
    Ok(written)
}

/// A column name as a file name: characters other than letters, digits, `-`, `_` and `.`
/// become `_` (a name may hold `/`).
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The axis title of a history column: the quantity in words for the known ones.
pub fn axis_name(column: &str) -> &str {
    match column {
        "lambda" => "load factor λ",
        "time" => "time t",
        "energy" => "stored energy",
        "work" => "external work",
        "wall_seconds" => "wall time [s]",
        "newton_iterations" => "Newton iterations",
        "heat_stored" => "heat stored",
        "heat_in" => "heat supplied",
        other => other,
    }
}

/// What the columns of a results folder measure and the units its case named, from its
/// `summary.json` (none for a folder without one, such as an older run's).
#[derive(Debug, Default)]
pub struct Labels {
    /// Column → quantity ("length", "force", …).
    quantities: std::collections::BTreeMap<String, String>,
    /// Quantity → unit.
    units: std::collections::BTreeMap<String, String>,
}

impl Labels {
    pub fn read(dir: &Path) -> Labels {
        let Ok(text) = std::fs::read_to_string(dir.join("summary.json")) else {
            return Labels::default();
        };
        let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) else {
            return Labels::default();
        };
        let map = |key: &str| {
            json.get(key)
                .and_then(|m| m.as_object())
                .map(|m| {
                    m.iter()
                        .filter_map(|(k, v)| Some((k.clone(), v.as_str()?.to_string())))
                        .collect()
                })
                .unwrap_or_default()
        };
        Labels {
            quantities: map("quantities"),
            units: map("units"),
        }
    }

    /// The x column where none is asked for: the physical time where the run has one, else λ.
    pub fn default_x(&self) -> &'static str {
        if self.quantities.contains_key("time") {
            "time"
        } else {
            "lambda"
        }
    }

    /// [`Labels::default_x`] for the history `h`: the pseudo-time where λ holds while it runs
    /// on (a `path` that presses and then slides at full load), where λ would draw the slide
    /// as one vertical line.
    pub fn default_x_of(&self, h: &History) -> &'static str {
        let x = self.default_x();
        let (Some(lambda), Some(time)) = (h.column("lambda"), h.column("time")) else {
            return x;
        };
        let held = (1..lambda.len()).any(|i| lambda[i] <= lambda[i - 1] && time[i] > time[i - 1]);
        if held { "time" } else { x }
    }

    /// The axis title of `column`: its name or the quantity in words, then the unit in
    /// brackets, or the quantity where the case named no unit for it (`gap [mm]`,
    /// `R_bottom_y [force]`).
    pub fn axis(&self, column: &str) -> String {
        let name = axis_name(column);
        match self.quantities.get(column) {
            Some(q) => format!("{name} [{}]", self.units.get(q).unwrap_or(q)),
            None => name.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short_and_zero_is_zero() {
        assert_eq!(tick_label(0.1, 1.0, false), "0.1");
        assert_eq!(tick_label(0.25, 0.25, false), "0.25");
        assert_eq!(tick_label(-2.220446e-16, 0.25, false), "0");
        assert_eq!(tick_label(1.5e-7, 2e-6, false), "1.5e-7");
        assert_eq!(tick_label(20000.0, 20000.0, false), "20000");
        assert_eq!(tick_label(2e5, 1e6, false), "2e5");
        assert_eq!(tick_label(1e-3, 1.0, true), "1e-3");
        assert_eq!(tick_label(5e-3, 1.0, true), "5e-3");
        assert_eq!(tick_label(8e-3, 1.0, true), "");
    }
}
