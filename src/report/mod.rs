//! Reports: SVG line plots (plotters, no system fonts), Markdown and self-contained HTML (inline SVG, no
//! network), and the JSON behind every table. Every file is written atomically.

pub mod text;

use plotters::prelude::*;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

pub mod outdir;
pub use outdir::{check_output_dir, check_output_file, replace_output_dir};

/// Report-writing failures.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Drawing failed.
    #[error("plot '{title}': {detail}")]
    Plot { title: String, detail: String },
    /// The output directory may not be replaced (it holds something flightid did not write): bad input.
    #[error("refusing to write {}: it {reason}", crate::text::escape_control(&path.display().to_string()))]
    Refused { path: PathBuf, reason: String },
    /// File system.
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// One curve of a plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissa values.
    pub x: Vec<f64>,
    /// Ordinate values (non-finite points are skipped).
    pub y: Vec<f64>,
    /// Reference curve (e.g. the JSBSim linearization): drawn as a wide translucent band under the others.
    pub reference: bool,
}

impl Series {
    /// A solid curve.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series {
            label: label.into(),
            x,
            y,
            reference: false,
        }
    }
}

/// A line plot with labelled axes (units in the labels) and a legend.
#[derive(Debug, Clone)]
pub struct LinePlot {
    /// Caption.
    pub title: String,
    /// Abscissa label with unit, e.g. `time, s`.
    pub x_label: String,
    /// Ordinate label with unit, e.g. `theta, deg`.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
    /// Logarithmic abscissa (Bode plots).
    pub log_x: bool,
}

/// Colours of series that are not a known model: none of them is a model's fixed colour below.
const PALETTE: [RGBColor; 6] = [
    RGBColor(44, 160, 44),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 128),
];

/// Fixed colours of the models every report shows, so a model looks the same in every plot.
const MODEL_COLORS: [(&str, RGBColor); 7] = [
    ("JSBSim nonlinear", RGBColor(0, 0, 0)),
    ("JSBSim linearization", RGBColor(120, 120, 120)),
    ("jsbsim_linearization", RGBColor(120, 120, 120)),
    ("ls", RGBColor(214, 39, 40)),
    ("iv", RGBColor(148, 103, 189)),
    ("srivc", RGBColor(31, 119, 180)),
    ("oe", RGBColor(255, 127, 14)),
];

/// Plot size in px: the chart on the left, the legend column on the right (legends never cover curves).
const PLOT_W: u32 = 960;
const PLOT_H: u32 = 420;
const LEGEND_W: u32 = 210;

/// A series drawn with fewer points than this gets a marker on each point (sparse data: sweeps, campaigns).
const MARKER_BELOW_POINTS: usize = 40;

/// The colour of a series: the model's fixed colour when the label names a known model (optionally followed by
/// a note in parentheses, `ls (clipped)`, or after `ours: `), else light grey for a reference curve, else the
/// palette by position.
fn series_color(series: &Series, i: usize) -> RGBColor {
    let label = series.label.strip_prefix("ours: ").unwrap_or(&series.label);
    let fixed = MODEL_COLORS.iter().find(|(name, _)| {
        label == *name
            || label
                .strip_prefix(name)
                .is_some_and(|rest| rest.starts_with(" ("))
    });
    match fixed {
        Some((_, c)) => *c,
        None if series.reference => RGBColor(150, 150, 150),
        None => PALETTE[i % PALETTE.len()],
    }
}

/// The line a series is drawn with, in the plot and in its legend swatch: a reference curve is a wide
/// translucent band, so it stays visible under models that lie on it.
fn line_style(series: &Series, color: RGBColor) -> ShapeStyle {
    if series.reference {
        color.mix(0.45).stroke_width(7)
    } else {
        color.stroke_width(2)
    }
}

fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    (lo <= hi).then_some((lo, hi))
}

/// Renders a line plot to SVG text (960 × 420 px: chart, then a legend column on the right).
pub fn line_plot_svg(plot: &LinePlot) -> Result<String, ReportError> {
    let err = |e: String| ReportError::Plot {
        title: plot.title.clone(),
        detail: e,
    };
    let (x0, x1) = finite_range(
        plot.series
            .iter()
            .flat_map(|s| s.x.iter().copied())
            .filter(|x| !plot.log_x || *x > 0.0),
    )
    .ok_or_else(|| err("no finite x values".into()))?;
    let (mut y0, mut y1) = finite_range(plot.series.iter().flat_map(|s| s.y.iter().copied()))
        .ok_or_else(|| err("no finite y values".into()))?;
    let pad = if y1 > y0 {
        0.06 * (y1 - y0)
    } else {
        y0.abs().max(1e-9) * 0.1
    };
    y0 -= pad;
    y1 += pad;
    let (x0, x1) = if x1 > x0 {
        (x0, x1)
    } else if plot.log_x {
        (x0 / 2.0, x0 * 2.0)
    } else {
        (x0 - 1.0, x0 + 1.0)
    };
    // sparse series get markers: keep the end points off the axes
    let (x0, x1) = if !plot.log_x && plot.series.iter().any(|s| s.x.len() < MARKER_BELOW_POINTS) {
        let pad = 0.03 * (x1 - x0);
        (x0 - pad, x1 + pad)
    } else {
        (x0, x1)
    };
    let colors: Vec<RGBColor> = plot
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| series_color(s, i))
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (PLOT_W, PLOT_H)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let (chart_area, legend_area) = root.split_horizontally(PLOT_W - LEGEND_W);
        let mut builder = ChartBuilder::on(&chart_area);
        builder
            .caption(&plot.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(plot.x_label.as_str())
                    .y_desc(plot.y_label.as_str())
                    .label_style(("sans-serif", 12))
                    .draw()
                    .map_err(|e| err(e.to_string()))?;
                for (s, &color) in plot.series.iter().zip(&colors) {
                    let points: Vec<(f64, f64)> =
                        s.x.iter()
                            .zip(&s.y)
                            .filter(|(x, y)| {
                                x.is_finite() && y.is_finite() && (!plot.log_x || **x > 0.0)
                            })
                            .map(|(x, y)| (*x, *y))
                            .collect();
                    if points.len() < MARKER_BELOW_POINTS {
                        chart
                            .draw_series(points.iter().map(|p| Circle::new(*p, 4, color.filled())))
                            .map_err(|e| err(e.to_string()))?;
                    }
                    chart
                        .draw_series(LineSeries::new(points, line_style(s, color)))
                        .map_err(|e| err(e.to_string()))?;
                }
            }};
        }
        if plot.log_x {
            draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(|e| err(e.to_string()))?);
        } else {
            draw!(builder
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| err(e.to_string()))?);
        }
        draw_legend(&legend_area, plot, &colors).map_err(err)?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(svg)
}

/// The legend column: one swatch (line, plus a marker for sparse series) and label per series.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    plot: &LinePlot,
    colors: &[RGBColor],
) -> Result<(), String> {
    let font = ("sans-serif", 12).into_font();
    let row_h = 20;
    let top = 46;
    for (k, (s, &color)) in plot.series.iter().zip(colors).enumerate() {
        let y = top + row_h * k as i32;
        if y + row_h > PLOT_H as i32 {
            break;
        }
        area.draw(&PathElement::new(
            vec![(6, y), (30, y)],
            line_style(s, color),
        ))
        .map_err(|e| e.to_string())?;
        if s.x.len() < MARKER_BELOW_POINTS {
            area.draw(&Circle::new((18, y), 4, color.filled()))
                .map_err(|e| e.to_string())?;
        }
        let max_chars = 28;
        let label: String = if s.label.chars().count() > max_chars {
            s.label.chars().take(max_chars - 1).collect::<String>() + "…"
        } else {
            s.label.clone()
        };
        area.draw(&Text::new(label, (36, y - 6), font.clone().color(&BLACK)))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// A table: header and rows of already formatted cells.
#[derive(Debug, Clone, Serialize)]
pub struct Table {
    /// Caption.
    pub caption: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with fixed column headers.
    pub fn new(caption: impl Into<String>, header: &[&str], rows: Vec<Vec<String>>) -> Self {
        Table {
            caption: caption.into(),
            header: header.iter().map(|h| h.to_string()).collect(),
            rows,
        }
    }
}

/// A report section.
#[derive(Debug, Clone, Default)]
pub struct Section {
    /// Heading.
    pub heading: String,
    /// Paragraphs of plain text.
    pub paragraphs: Vec<String>,
    /// Tables.
    pub tables: Vec<Table>,
    /// Plots: (file stem, plot).
    pub plots: Vec<(String, LinePlot)>,
}

/// A whole report.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Title.
    pub title: String,
    /// Sections in order.
    pub sections: Vec<Section>,
}

/// Writes `bytes` to `path` through a temporary file and a rename: readers never see a partial file. Missing
/// parent directories are made (as `mkdir -p` would).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    let io = |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn markdown_table(t: &Table) -> String {
    let mut s = format!(
        "**{}**\n\n| {} |\n|{}\n",
        t.caption,
        t.header.join(" | "),
        "---|".repeat(t.header.len())
    );
    for r in &t.rows {
        s.push_str(&format!("| {} |\n", r.join(" | ")));
    }
    s.push('\n');
    s
}

fn html_table(t: &Table) -> String {
    let mut s = format!("<table><caption>{}</caption><tr>", html_escape(&t.caption));
    for h in &t.header {
        s.push_str(&format!("<th>{}</th>", html_escape(h)));
    }
    s.push_str("</tr>");
    for r in &t.rows {
        s.push_str("<tr>");
        for c in r {
            s.push_str(&format!("<td>{}</td>", html_escape(c)));
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>\n");
    s
}

/// Writes `dir/index.html` (self-contained), `dir/report.md`, one `dir/NAME.svg` per plot and `dir/report.json`.
/// Returns the path of `index.html`.
pub fn write_report(
    dir: &Path,
    report: &Report,
    json: &serde_json::Value,
) -> Result<PathBuf, ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| ReportError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    // Render every plot first: a drawing failure leaves nothing behind.
    let mut rendered = Vec::new();
    for section in &report.sections {
        let mut svgs = Vec::new();
        for (name, plot) in &section.plots {
            svgs.push((name.clone(), plot.title.clone(), line_plot_svg(plot)?));
        }
        rendered.push(svgs);
    }
    let mut md = format!("# {}\n\n", report.title);
    let mut html = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{0}</title><style>\
         body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}\
         table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:3px 8px;text-align:right}}\
         caption{{font-weight:bold;text-align:left;padding:4px 0}}figure{{margin:1em 0}}</style></head><body><h1>{0}</h1>\n",
        html_escape(&report.title)
    );
    for (section, svgs) in report.sections.iter().zip(&rendered) {
        md.push_str(&format!("## {}\n\n", section.heading));
        html.push_str(&format!("<h2>{}</h2>\n", html_escape(&section.heading)));
        for p in &section.paragraphs {
            md.push_str(&format!("{p}\n\n"));
            html.push_str(&format!("<p>{}</p>\n", html_escape(p)));
        }
        for t in &section.tables {
            md.push_str(&markdown_table(t));
            html.push_str(&html_table(t));
        }
        for (name, title, svg) in svgs {
            write_atomic(&dir.join(format!("{name}.svg")), svg.as_bytes())?;
            md.push_str(&format!("![{title}]({name}.svg)\n\n"));
            html.push_str(&format!("<figure id=\"{name}\">{svg}</figure>\n"));
        }
    }
    html.push_str("</body></html>\n");
    let json_text = serde_json::to_string_pretty(json).unwrap_or_else(|_| "{}".into());
    write_atomic(&dir.join("report.json"), json_text.as_bytes())?;
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    let index = dir.join("index.html");
    write_atomic(&index, html.as_bytes())?;
    Ok(index)
}

/// Writes a whole report directory atomically through [`replace_output_dir`]: [`write_report`] fills a sibling
/// temporary directory, which then takes the place of `dir`, so a reader sees the old report or the new one,
/// never a mix or a partial one. An existing `dir` is replaced only when it is empty or holds nothing but an
/// earlier flightid output (see [`outdir`]). Returns the path of `index.html`.
pub fn write_report_dir(
    dir: &Path,
    report: &Report,
    json: &serde_json::Value,
) -> Result<PathBuf, ReportError> {
    replace_output_dir(dir, |tmp| write_report(tmp, report, json))?;
    Ok(dir.join("index.html"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_holds_inline_svg_with_axis_labels_and_legend() {
        let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.05).collect();
        let plot = LinePlot {
            title: "theta response".into(),
            x_label: "time, s".into(),
            y_label: "theta, deg".into(),
            series: vec![
                Series::new("nonlinear", t.clone(), t.iter().map(|x| x.sin()).collect()),
                Series::new(
                    "linear",
                    t.clone(),
                    t.iter().map(|x| 0.9 * x.sin()).collect(),
                ),
            ],
            log_x: false,
        };
        let dir = tempfile::tempdir().unwrap();
        let report = Report {
            title: "test".into(),
            sections: vec![Section {
                heading: "overlay".into(),
                paragraphs: vec!["a < b".into()],
                tables: vec![Table::new(
                    "fit",
                    &["model", "fit %"],
                    vec![vec!["ls".into(), "99.1".into()]],
                )],
                plots: vec![("theta".into(), plot)],
            }],
        };
        let index = write_report(dir.path(), &report, &serde_json::json!({"fit": 99.1})).unwrap();
        let html = std::fs::read_to_string(index).unwrap();
        assert!(html.contains("<svg") && html.contains("time, s") && html.contains("theta, deg"));
        assert!(
            html.contains("nonlinear")
                && html.contains("a &lt; b")
                && html.contains("<td>99.1</td>")
        );
        assert!(
            !html.contains("http://") || html.matches("http://").all(|_| html.contains("xmlns")),
            "no external links"
        );
        assert!(dir.path().join("theta.svg").exists() && dir.path().join("report.md").exists());
    }

    #[test]
    fn empty_plot_is_an_error_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let plot = LinePlot {
            title: "empty".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![],
            log_x: false,
        };
        let report = Report {
            title: "t".into(),
            sections: vec![Section {
                plots: vec![("e".into(), plot)],
                ..Default::default()
            }],
        };
        assert!(write_report(dir.path(), &report, &serde_json::json!({})).is_err());
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
    }

    #[test]
    fn report_directory_is_replaced_whole_and_a_foreign_directory_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let plot = |title: &str| LinePlot {
            title: title.into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![Series::new("ls", vec![0.0, 1.0], vec![1.0, 2.0])],
            log_x: false,
        };
        let report = |stem: &str| Report {
            title: "t".into(),
            sections: vec![Section {
                plots: vec![(stem.into(), plot(stem))],
                ..Default::default()
            }],
        };
        write_report_dir(&dir, &report("first"), &serde_json::json!({})).unwrap();
        assert!(dir.join("first.svg").exists());
        // a second report replaces the first whole: no stale plot of the first survives
        let index = write_report_dir(&dir, &report("second"), &serde_json::json!({})).unwrap();
        assert!(index.exists() && dir.join("second.svg").exists());
        assert!(!dir.join("first.svg").exists());
        // no temporary directories are left beside it
        let names: Vec<String> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        assert_eq!(names, vec!["out".to_string()]);
        // a directory holding something else is never replaced
        let foreign = tmp.path().join("home");
        std::fs::create_dir(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "keep").unwrap();
        assert!(write_report_dir(&foreign, &report("x"), &serde_json::json!({})).is_err());
        assert!(foreign.join("notes.txt").exists());
    }
}
