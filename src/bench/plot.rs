//! The benchmarks' plots, as SVG text (`plotters`): culling time against scene size, and each
//! MSAA method's frame time against its image error, and levels of detail likewise.

use super::culling::CullingReport;
use super::lod::LodReport;
use super::msaa::MsaaReport;
use plotters::coord::Shift;
use plotters::prelude::*;

/// One color per series, in order.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// An axis label: at most four significant decimals, no trailing zeros.
fn label(v: &f64) -> String {
    let digits = if v.abs() >= 100.0 { 0 } else { (4 - v.abs().max(1e-9).log10().ceil() as i32).clamp(0, 6) as usize };
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

fn plot_error(e: impl std::fmt::Display) -> crate::Error {
    crate::Error::Invalid(format!("plot: {e}"))
}

/// A log axis range around `values` (positive ones), a little wider on both sides.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) =
        values.filter(|v| *v > 0.0 && v.is_finite()).fold((f64::MAX, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    if hi <= 0.0 {
        return 0.1..1.0;
    }
    (lo / 1.5)..(hi * 1.5)
}

/// Frame milliseconds of each graph against the city's instance count (left), and all culling
/// work of each culling graph beside the naive frustum peer (right), both log-log.
pub fn culling_svg(report: &CullingReport) -> crate::Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1100, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (left, right) = root.split_horizontally(550);
        let instances = || report.scenes.iter().map(|s| s.instances as f64);
        let graphs: Vec<&str> =
            report.scenes.first().map(|s| s.graphs.iter().map(|g| g.graph.as_str()).collect()).unwrap_or_default();
        let series = |pick: &dyn Fn(&super::culling::GraphFigure) -> f64| -> Vec<(String, Vec<(f64, f64)>)> {
            graphs
                .iter()
                .map(|&name| {
                    let points = report
                        .scenes
                        .iter()
                        .filter_map(|s| {
                            s.graphs.iter().find(|g| g.graph == name).map(|g| (s.instances as f64, pick(g)))
                        })
                        .filter(|(_, y)| *y > 0.0)
                        .collect();
                    (name.to_string(), points)
                })
                .collect()
        };
        let frames = series(&|g| g.frame_ms);
        let mut culling = series(&|g| g.culling_ms);
        culling.retain(|(_, points)| !points.is_empty());
        culling.push((
            "naive frustum peer".into(),
            report.scenes.iter().map(|s| (s.instances as f64, s.naive_peer_ms)).collect(),
        ));
        let caption = format!("frame, {} ({}x{})", report.device, report.width, report.height);
        lines_log_log(&left, &caption, "GPU ms per frame", &frames, log_range(instances()))?;
        lines_log_log(&right, "all culling work", "GPU ms", &culling, log_range(instances()))?;
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

/// One log-log panel: instances across, milliseconds up, a line per series.
fn lines_log_log(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    caption: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    x_range: std::ops::Range<f64>,
) -> crate::Result<()> {
    let y_range = log_range(series.iter().flat_map(|(_, p)| p.iter().map(|(_, y)| *y)));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("instances")
        .y_desc(y_desc)
        .x_label_formatter(&label)
        .y_label_formatter(&label)
        .draw()
        .map_err(plot_error)?;
    for (i, (name, points)) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(points.iter().copied(), color.stroke_width(2)))
            .map_err(plot_error)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2)));
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(plot_error)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(plot_error)
}

/// Each method's frame milliseconds (across, log) against its mean FLIP (up), one panel per
/// scene, at the report's middle light count; points are labelled with their sample count.
/// `None` when the report has no image errors.
pub fn msaa_svg(report: &MsaaReport) -> crate::Result<Option<String>> {
    if report.rows.iter().all(|r| r.mean_flip.is_none()) {
        return Ok(None);
    }
    let mut scenes: Vec<&str> = Vec::new();
    let mut lights: Vec<usize> = Vec::new();
    let mut methods: Vec<&str> = Vec::new();
    for r in &report.rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !lights.contains(&r.lights) {
            lights.push(r.lights);
        }
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    lights.sort_unstable();
    let light = lights[lights.len() / 2];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (560 * scenes.len() as u32, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        for (panel, scene) in root.split_evenly((1, scenes.len())).iter().zip(&scenes) {
            let rows: Vec<_> = report.rows.iter().filter(|r| r.scene == *scene && r.lights == light).collect();
            let x_range = log_range(rows.iter().map(|r| r.frame_ms));
            let flip_max = rows.iter().filter_map(|r| r.mean_flip).fold(0.0f64, f64::max).max(1e-4) * 1.15;
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("{scene}, {light} lights: speed against error"), ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(64)
                .build_cartesian_2d(x_range.log_scale(), 0.0..flip_max)
                .map_err(plot_error)?;
            chart
                .configure_mesh()
                .x_desc("GPU ms per frame")
                .x_label_formatter(&label)
                .y_label_formatter(&label)
                .y_desc(format!("mean FLIP against {} spp", report.reference_samples.unwrap_or(0)))
                .draw()
                .map_err(plot_error)?;
            for (i, method) in methods.iter().enumerate() {
                let color = PALETTE[i % PALETTE.len()];
                let points: Vec<(f64, f64, u32)> = rows
                    .iter()
                    .filter(|r| r.method == *method)
                    .filter_map(|r| r.mean_flip.map(|f| (r.frame_ms, f, r.samples)))
                    .collect();
                chart
                    .draw_series(points.iter().map(|&(x, y, samples)| {
                        EmptyElement::at((x, y))
                            + Circle::new((0, 0), 4, color.filled())
                            + Text::new(format!("{samples}x"), (6, -12), ("sans-serif", 11).into_font())
                    }))
                    .map_err(plot_error)?
                    .label(*method)
                    .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(Some(svg))
}

/// One configuration of the LOD plot: frame ms, error, threshold.
type Point = (f64, f64, f64);

/// Each scene's frame time against its image error at each level-of-detail threshold (error
/// against the supersampled reference, or against full detail without one), the thresholds in
/// order joined by a line, one line without cluster culling and one with it: the points below
/// and left of the others are the ones worth taking.
pub fn lod_svg(report: &LodReport) -> crate::Result<Option<String>> {
    let with_reference = report.rows.iter().any(|r| r.flip_vs_reference.is_some());
    let error = |r: &super::lod::LodFigure| if with_reference { r.flip_vs_reference } else { r.flip_vs_full };
    if report.rows.iter().all(|r| error(r).is_none()) {
        return Ok(None);
    }
    let mut scenes: Vec<&str> = Vec::new();
    for r in &report.rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (560 * scenes.len() as u32, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        for (panel, scene) in root.split_evenly((1, scenes.len())).iter().zip(&scenes) {
            let rows = report.rows.iter().filter(|r| r.scene == *scene);
            // One curve without cluster culling and one with it, where the run has both.
            let series: Vec<(bool, Vec<Point>)> = [false, true]
                .into_iter()
                .map(|on| {
                    let points = rows.clone().filter(|r| r.clusters == on);
                    (on, points.filter_map(|r| error(r).map(|e| (r.frame_ms, e, r.threshold))).collect())
                })
                .filter(|(_, points): &(bool, Vec<_>)| !points.is_empty())
                .collect();
            let all = || series.iter().flat_map(|(_, p)| p.iter());
            let x_range = log_range(all().map(|p| p.0));
            let flip_max = all().map(|p| p.1).fold(0.0f64, f64::max).max(1e-4) * 1.15;
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("{scene}: frame time against error"), ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(64)
                .build_cartesian_2d(x_range.log_scale(), 0.0..flip_max)
                .map_err(plot_error)?;
            let against = match report.reference_samples {
                Some(n) if with_reference => format!("{n} spp reference"),
                _ => "full detail".into(),
            };
            chart
                .configure_mesh()
                .x_desc("GPU ms per frame")
                .x_label_formatter(&label)
                .y_label_formatter(&label)
                .y_desc(format!("mean FLIP against {against}"))
                .draw()
                .map_err(plot_error)?;
            for (on, points) in &series {
                let color = PALETTE[*on as usize];
                let name = if *on { "cluster culling" } else { "instances only" };
                chart
                    .draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), color))
                    .map_err(plot_error)?
                    .label(name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
                chart
                    .draw_series(points.iter().map(|&(x, y, threshold)| {
                        EmptyElement::at((x, y))
                            + Circle::new((0, 0), 4, color.filled())
                            + Text::new(format!("{} px", label(&threshold)), (6, -12), ("sans-serif", 11).into_font())
                    }))
                    .map_err(plot_error)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(Some(svg))
}
