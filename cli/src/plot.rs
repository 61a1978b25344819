//! `cadr bench --plot FILE.svg|FILE.png`: the technique table as bars of CPU µs per frame on a
//! log scale, or a sweep as lines of cost against scene size, drawn with `plotters`.

use std::ops::Range;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

/// Fonts tried for the labels when `CADR_PLOT_FONT` names none (Debian's fonts-dejavu-core
/// first).
const FONT_CANDIDATES: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// The variable naming a TrueType font for the labels.
const FONT_VARIABLE: &str = "CADR_PLOT_FONT";

/// One line of a sweep chart: a technique's CPU µs per frame at each scene size.
pub struct Series {
    pub label: String,
    pub points: Vec<(u64, f64)>,
}

/// Where a chart goes, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Svg,
    Png,
}

fn format_of(path: &Path) -> Result<Format, String> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(format!(
            "--plot {}: expected a file ending in .svg or .png",
            path.display()
        )),
    }
}

/// Checks `--plot`'s file name before a benchmark spends its time.
pub fn check_path(path: &Path) -> Result<(), String> {
    format_of(path)?;
    register_font()
}

/// Registers the labels' font with plotters, once per process.
fn register_font() -> Result<(), String> {
    static REGISTERED: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let chosen = std::env::var_os(FONT_VARIABLE).map(std::path::PathBuf::from);
            let path = match &chosen {
                Some(path) => path.clone(),
                None => FONT_CANDIDATES
                    .iter()
                    .map(std::path::PathBuf::from)
                    .find(|p| p.is_file())
                    .ok_or_else(|| {
                        format!(
                            "--plot needs a TrueType font for its labels: install fonts-dejavu-core or set {FONT_VARIABLE} to a .ttf file"
                        )
                    })?,
            };
            let bytes = std::fs::read(&path)
                .map_err(|e| format!("{FONT_VARIABLE} {}: {e}", path.display()))?;
            // plotters keeps registered fonts for the life of the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| format!("{}: not a TrueType font plotters can read", path.display()))
        })
        .clone()
}

/// What a chart shows.
enum Chart<'a> {
    /// One bar per row: its label and CPU µs per frame.
    Bars {
        title: &'a str,
        rows: &'a [(String, f64)],
    },
    /// One line per technique over scene sizes.
    Lines {
        title: &'a str,
        /// The x and y axes' names.
        axes: (&'a str, &'a str),
        series: &'a [Series],
    },
}

/// Writes the technique table as horizontal bars of CPU µs per frame (log scale), one per
/// `(label, cpu_us)` row, to `path` (.svg or .png).
pub fn bars(path: &Path, title: &str, rows: &[(String, f64)]) -> Result<(), String> {
    let height = 90 + 26 * rows.len().max(1) as u32;
    write(path, (1400, height), &Chart::Bars { title, rows })
}

/// Writes a sweep as lines of a cost against scene size (both log scales), the axes named
/// by `axes` (x, y; "(log scale)" is added).
pub fn lines(
    path: &Path,
    title: &str,
    axes: (&str, &str),
    series: &[Series],
) -> Result<(), String> {
    write(
        path,
        (1100, 700),
        &Chart::Lines {
            title,
            axes,
            series,
        },
    )
}

fn write(path: &Path, size: (u32, u32), chart: &Chart<'_>) -> Result<(), String> {
    register_font()?;
    let failed = |e: String| format!("cannot draw {}: {e}", path.display());
    match format_of(path)? {
        Format::Svg => {
            let area = SVGBackend::new(path, size).into_drawing_area();
            draw(&area, chart).map_err(failed)?;
            area.present().map_err(|e| failed(e.to_string()))
        }
        Format::Png => {
            let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
            {
                let area = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
                draw(&area, chart).map_err(failed)?;
                area.present().map_err(|e| failed(e.to_string()))?;
            }
            image::RgbImage::from_raw(size.0, size.1, pixels)
                .ok_or_else(|| failed("the picture has the wrong size".into()))?
                .save_with_format(path, image::ImageFormat::Png)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        }
    }
}

/// A log axis range holding every value in `values` (positive ones), with some room.
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (low, high) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if low > high {
        return 0.1..10.0;
    }
    (low / 2.0)..(high * 2.0)
}

fn draw<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, chart: &Chart<'_>) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    area.fill(&WHITE).map_err(err)?;
    match chart {
        Chart::Bars { title, rows } => {
            let x_range = log_range(rows.iter().map(|(_, v)| *v));
            let floor = x_range.start;
            let count = rows.len();
            // Row i (the baseline first) is drawn at the top: segment count - 1 - i.
            let label_of = |segment: usize| rows.get(count.checked_sub(segment + 1)?);
            // A range 0..n has a segment at each of 0..=n; one row still needs a range.
            let last_segment = count.saturating_sub(1).max(1);
            let mut chart = ChartBuilder::on(area)
                .caption(*title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(520)
                .build_cartesian_2d(x_range.log_scale(), (0..last_segment).into_segmented())
                .map_err(err)?;
            chart
                .configure_mesh()
                .disable_y_mesh()
                .y_labels(count.max(1))
                .y_label_formatter(&|segment| match segment {
                    SegmentValue::CenterOf(index) => {
                        label_of(*index).map_or(String::new(), |(label, _)| label.clone())
                    }
                    _ => String::new(),
                })
                .x_desc("CPU µs per frame (log scale)")
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(rows.iter().enumerate().map(|(i, (_, cpu_us))| {
                    let segment = count - 1 - i;
                    let colour = if i == 0 { RED.mix(0.7) } else { BLUE.mix(0.6) };
                    let mut bar = Rectangle::new(
                        [
                            (floor, SegmentValue::Exact(segment)),
                            (cpu_us.max(floor), SegmentValue::Exact(segment + 1)),
                        ],
                        colour.filled(),
                    );
                    bar.set_margin(3, 3, 0, 0);
                    bar
                }))
                .map_err(err)?;
            chart
                .draw_series(rows.iter().enumerate().map(|(i, (_, cpu_us))| {
                    Text::new(
                        format!(" {cpu_us:.1}"),
                        (cpu_us.max(floor), SegmentValue::CenterOf(count - 1 - i)),
                        ("sans-serif", 12).into_font(),
                    )
                }))
                .map_err(err)?;
        }
        Chart::Lines {
            title,
            axes,
            series,
        } => {
            let x_range = log_range(
                series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|(n, _)| *n as f64)),
            );
            let y_range = log_range(series.iter().flat_map(|s| s.points.iter().map(|(_, v)| *v)));
            let mut chart = ChartBuilder::on(area)
                .caption(*title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(format!("{} (log scale)", axes.0))
                .y_desc(format!("{} (log scale)", axes.1))
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(err)?;
            for (index, line) in series.iter().enumerate() {
                let colour = Palette99::pick(index).to_rgba();
                chart
                    .draw_series(LineSeries::new(
                        line.points.iter().map(|(n, v)| (*n as f64, *v)),
                        colour.stroke_width(2),
                    ))
                    .map_err(err)?
                    .label(line.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .draw()
                .map_err(err)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_of_one_row_is_drawn_and_other_extensions_are_refused() {
        let path = std::env::temp_dir().join(format!("cadr-plot-{}.svg", std::process::id()));
        let rows = [("baseline (built-in) [solid]".to_owned(), 123.0)];
        bars(&path, "one row", &rows).expect("draw");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.contains("baseline (built-in) [solid]"));
        let _ = std::fs::remove_file(&path);
        assert!(check_path(Path::new("table.pdf")).is_err());
    }
}
