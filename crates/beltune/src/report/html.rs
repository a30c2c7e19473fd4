//! The self-contained report page: inline CSS, no network. Every figure is an
//! inline SVG ([`super::plot`]); the figures with an interactive version
//! ([`super::chart`]) show it on screen instead (uPlot and beltune's plots on
//! it, [`super::web`], inlined with the charts' data as JSON): zoom, a read-out
//! on hover, log frequency axes. Printing shows the SVG (`@media print`), and
//! so does a browser without scripts.

use super::data::Report;
use super::{plot, web};
use crate::{Error, Result};
use minijinja::value::Serde;
use minijinja::{context, Environment, Value};

const TEMPLATE: &str = r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{{ title }}</title>
<style>
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 2em auto; max-width: 960px; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; border-bottom: 1px solid #ccc; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0; }
td, th { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th { background: #f2f2f2; } td:first-child, th:first-child { text-align: left; }
.summary { background: #f6f8fa; padding: 0.8em 1em; border-left: 4px solid #1f77b4; }
.verdict { padding: 0.8em 1em; border: 2px solid; margin: 1em 0; }
.verdict.pass { border-color: #2ca02c; background: #f0faf0; }
.verdict.fail { border-color: #d62728; background: #fdf0f0; }
.verdict h2 { border: none; margin: 0 0 0.4em 0; }
.verdict .pass { color: #1a7a1a; font-weight: bold; } .verdict .fail { color: #b01c1c; font-weight: bold; }
.verdict table { background: #fff; }
.warn { color: #8a5a00; }
.next { font-weight: bold; }
.trace { font-size: 0.85em; color: #555; }
figure { margin: 0.5em 0; } figure svg { width: 100%; height: auto; }
pre { background: #f6f8fa; padding: 0.6em; font-size: 0.85em; white-space: pre-wrap; overflow-wrap: anywhere; }
figure .interactive { display: none; }
html.js figure .static.has-chart { display: none; }
html.js figure .interactive { display: block; }
.chart-title { font-size: 0.9em; color: #333; margin: 0.6em 0 0.1em; }
.plot-help { font-size: 0.8em; color: #555; margin: 0.2em 0; }
.plot { width: 100%; position: relative; }
@media print {
  html.js figure .static.has-chart { display: block; }
  html.js figure .interactive { display: none; }
  body { margin: 0; max-width: none; font-size: 10pt; }
  h2 { break-after: avoid; }
  figure, table, .verdict { break-inside: avoid; }
  .verdict { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
  pre { white-space: pre-wrap; }
  a { color: inherit; text-decoration: none; }
}
</style>
{% if charts %}<style>{{ uplot_css }}</style>
<style>{{ plot_css }}</style>{% endif %}
</head>
<body>
<h1>{{ title }}</h1>
{% if verdict %}<section id="verdict" class="verdict {{ 'pass' if verdict.passed else 'fail' }}">
<h2>Verdict: <span id="verdict-result" class="{{ 'pass' if verdict.passed else 'fail' }}">{{ verdict_word }}</span></h2>
{% if checks %}<table id="verdict-checks">
<tr><th>check</th><th>measured</th><th>limit</th><th>result</th></tr>
{% for c in checks %}<tr data-check="{{ c.name }}"><td>{{ c.description }}</td><td class="value" data-value="{{ c.value }}" data-unit="{{ c.unit }}">{{ c.value_text }} {{ c.display_unit }}</td><td>{{ c.relation }} {{ c.limit_text }} {{ c.display_unit }}</td><td class="{{ 'pass' if c.passed else 'fail' }}">{{ 'pass' if c.passed else 'FAIL' }}</td></tr>
{% endfor %}</table>{% endif %}
{% if verdict.warnings %}<ul id="verdict-warnings">{% for w in verdict.warnings %}<li class="warn"><b>{{ w.topic }}:</b> {{ w.reason }}</li>{% endfor %}</ul>{% else %}<p>No warnings (coherence, fit residual and margins are fine).</p>{% endif %}
<p class="next" id="next-step">Next step: {{ verdict.next_step }}</p>
</section>{% endif %}
<p class="summary">{{ summary }}</p>

{% if parameters %}<h2>Parameters</h2>
<table id="parameters">
<tr><th>quantity</th><th>unit</th><th>before (data sheet / default)</th><th>after (commissioned)</th>{% if has_truth %}<th>simulation truth</th>{% endif %}</tr>
{% for p in parameters %}<tr><td>{{ p.name }}</td><td>{{ p.unit }}</td><td>{{ p.before or "" }}</td><td class="after"{% if p.value is not none %} data-value="{{ p.value }}"{% endif %}>{{ p.after }}</td>{% if has_truth %}<td>{{ p.truth or "" }}</td>{% endif %}</tr>
{% endfor %}</table>{% endif %}

{% if validation_rows %}<h2>Validation</h2>
<table id="validation">
<tr><th>feedforward</th><th>max cart tracking error</th><th>static error</th><th>settling time</th></tr>
{% for r in validation_rows %}<tr><td>{{ r[0] }}</td><td>{{ r[1] }}</td><td>{{ r[2] }}</td><td>{{ r[3] }}</td></tr>
{% endfor %}</table>{% endif %}

{% for t in tables %}<h2>{{ t.title }}</h2>
<table class="extra">
<tr>{% for h in t.header %}<th>{{ h }}</th>{% endfor %}</tr>
{% for r in t.rows %}<tr>{% for c in r %}<td>{{ c }}</td>{% endfor %}</tr>
{% endfor %}</table>
{% endfor %}

{% for fig in figures %}<h2>{{ fig.heading }}</h2>
<figure id="{{ fig.id }}"><div class="static{% if fig.chart %} has-chart{% endif %}">{{ fig.svg }}</div>{% if fig.chart %}<div class="interactive"></div>{% endif %}</figure>
{% endfor %}

{% if data_files %}<h2>Data files</h2>
<ul>{% for f in data_files %}<li><a href="{{ f[0] }}">{{ f[0] }}</a>: {{ f[1] }}</li>{% endfor %}</ul>{% endif %}

{% if provenance %}<h2>Traceability</h2>
<table id="provenance" class="trace">
<tr><th>beltune version</th><td>{{ provenance.beltune_version }}</td></tr>
<tr><th>created (UTC)</th><td>{{ provenance.created_utc }}</td></tr>
<tr><th>command</th><td><code>{{ command_line }}</code></td></tr>
{% if provenance.seed is not none %}<tr><th>seed</th><td>{{ provenance.seed }}</td></tr>{% endif %}
</table>{% endif %}

{% if log %}<h2>Log</h2>
<pre id="log">{% for line in log %}{{ line }}
{% endfor %}</pre>{% endif %}
{% if charts %}<script type="application/json" id="chart-data">{{ charts }}</script>
<script>/* uPlot {{ uplot_version }} (https://github.com/leeoniya/uPlot), its licence:
{{ uplot_license }} */
{{ uplot_js }}</script>
<script>{{ plot_js }}</script>
<script>{{ init_js }}</script>{% endif %}
</body>
</html>
"#;

/// Draws the report's interactive charts (the data in `#chart-data`) into
/// their figures; panels of one figure zoom together.
const INIT_JS: &str = r#"(function () {
  'use strict';
  if (!window.uPlot || !window.BeltunePlot) return;
  const figures = JSON.parse(document.getElementById('chart-data').textContent);
  document.documentElement.classList.add('js');
  for (const fig of figures) {
    const host = document.querySelector('figure#' + fig.figure_id + ' > .interactive');
    if (!host) continue;
    const help = document.createElement('p');
    help.className = 'plot-help';
    help.textContent = 'Drag across a plot to zoom into it, double-click to zoom out; the line under a plot reads the values under the cursor.';
    host.appendChild(help);
    const plots = fig.panels.map((p, k) => {
      const cap = document.createElement('div');
      cap.className = 'chart-title';
      cap.textContent = p.title;
      host.appendChild(cap);
      const el = document.createElement('div');
      el.className = 'plot';
      el.id = fig.figure_id + '-chart-' + k;
      host.appendChild(el);
      return [el, p];
    });
    for (const [el, p] of plots) {
      p.onZoom = (min, max) => {
        for (const [other] of plots) {
          const u = other.uplot;
          if (other !== el && u && (u.scales.x.min !== min || u.scales.x.max !== max)) {
            u.setScale('x', { min: min, max: max });
          }
        }
      };
      window.BeltunePlot.draw(el, p);
    }
  }
}());"#;

/// Render the report to one self-contained HTML page: every plot an inline
/// SVG, and on screen an interactive chart where [`super::chart`] has one.
pub fn render_html(report: &Report) -> Result<String> {
    let charts = super::chart::report_charts(report);
    let has_chart = |id: &str| charts.iter().any(|c| c.figure_id == id);
    let mut figures: Vec<Value> = Vec::new();
    let mut add = |id: &str, heading: &str, svg: String| {
        figures.push(context! {
            id => id,
            heading => heading,
            svg => Value::from_safe_string(svg),
            chart => has_chart(id),
        });
    };
    if let Some(frf) = &report.frf {
        add(
            "frf",
            "Measured frequency response, coherence and fitted model",
            plot::frf_svg(frf)?,
        );
    }
    if let Some(e) = &report.excitation {
        add(
            "excitation",
            "Identification experiment",
            plot::excitation_svg(e)?,
        );
    }
    if let Some(c) = &report.controller {
        add("controller", "Controller", plot::bode_svg(c)?);
    }
    for (i, ol) in report.open_loops.iter().enumerate() {
        add(&format!("open-loop-{i}"), &ol.title, plot::bode_svg(ol)?);
    }
    for (i, cl) in report.closed_loops.iter().enumerate() {
        add(&format!("closed-loop-{i}"), &cl.title, plot::bode_svg(cl)?);
    }
    for (i, ov) in report.overlays.iter().enumerate() {
        add(&format!("overlay-{i}"), &ov.title, plot::bode_svg(ov)?);
    }
    if let Some(f) = &report.friction {
        add("friction", "Friction", plot::friction_svg(f)?);
    }
    for (i, t) in report.trends.iter().enumerate() {
        add(&format!("trend-{i}"), &t.title, plot::trend_svg(t)?);
    }
    if !report.moves.is_empty() {
        let limit = report.excitation.as_ref().map(|e| e.torque_limit_nm);
        add(
            "moves",
            "Validation moves",
            plot::moves_svg(&report.moves, limit)?,
        );
    }
    let mut env = Environment::new();
    env.add_template("report.html", TEMPLATE)
        .map_err(|e| Error::Report {
            reason: e.to_string(),
        })?;
    let tmpl = env.get_template("report.html").map_err(|e| Error::Report {
        reason: e.to_string(),
    })?;
    let checks: Vec<Value> = report
        .verdict
        .iter()
        .flat_map(|v| v.checks.iter())
        .map(|c| {
            context! {
                name => Value::from(Serde(&c.name)),
                description => c.name.description(),
                value => c.value,
                value_text => c.value_text(),
                limit_text => c.limit_text(),
                relation => c.relation(),
                display_unit => c.display_unit(),
                unit => &c.unit,
                passed => c.passed,
            }
        })
        .collect();
    let charts_value = if charts.is_empty() {
        Value::from(false)
    } else {
        Value::from_safe_string(super::chart::charts_json(&charts)?)
    };
    tmpl.render(context! {
        title => &report.title,
        checks => checks,
        verdict_word => report.verdict.as_ref().map(|v| v.word()).unwrap_or_default(),
        summary => &report.summary,
        verdict => Value::from(Serde(&report.verdict)),
        parameters => Value::from(Serde(&report.parameters)),
        has_truth => report.parameters.iter().any(|p| p.truth.is_some()),
        validation_rows => Value::from(Serde(&report.validation_rows)),
        tables => Value::from(Serde(&report.tables)),
        figures => figures,
        data_files => Value::from(Serde(&report.data_files)),
        provenance => Value::from(Serde(&report.provenance)),
        command_line => report.provenance.as_ref().map(|p| p.command_line_text()).unwrap_or_default(),
        log => Value::from(Serde(&report.log)),
        charts => charts_value,
        uplot_css => Value::from_safe_string(web::UPLOT_CSS.into()),
        plot_css => Value::from_safe_string(web::PLOT_CSS.into()),
        uplot_js => Value::from_safe_string(web::UPLOT_JS.into()),
        uplot_license => Value::from_safe_string(web::UPLOT_LICENSE.into()),
        uplot_version => web::UPLOT_VERSION,
        plot_js => Value::from_safe_string(web::PLOT_JS.into()),
        init_js => Value::from_safe_string(INIT_JS.into()),
    })
    .map_err(|e| Error::Report {
        reason: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::data::{FrictionPlot, ParameterRow};

    #[test]
    fn page_is_self_contained_and_escapes_text() {
        let r = Report {
            title: "axis <1>".into(),
            summary: "ok".into(),
            parameters: vec![ParameterRow {
                name: "m_c".into(),
                unit: "kg".into(),
                before: Some("11.57".into()),
                after: "13.44".into(),
                truth: None,
                value: Some(13.44),
            }],
            friction: Some(FrictionPlot {
                velocity_rad_s: vec![-10.0, 10.0],
                torque_nm: vec![-0.15, 0.15],
                viscous_nm_s_per_rad: 2.5e-3,
                coulomb_nm: 0.125,
            }),
            ..Default::default()
        };
        let mut r = r;
        let design = crate::design::design(
            &crate::design::DesignInput::new(crate::model::TwoMassParams::thesis_table_a4(), 1e-3),
            &crate::design::DesignKnobs::default(),
        )
        .unwrap();
        let moved = crate::commission::validation::MoveSummary {
            max_tracking_error_m: 2e-3,
            static_error_m: 20e-6,
            settling_time_s: Some(0.1),
            max_motor_error_m: 2e-3,
            max_torque_nm: 1.0,
        };
        r.verdict = Some(crate::verdict::judge(&crate::verdict::VerdictInput {
            limits: &crate::verdict::Limits::default(),
            validation: Some(crate::verdict::MoveInput {
                summary: &moved,
                record_after_move_s: 1.0,
                torque_max_nm: 3.1,
                on: crate::verdict::ValidatedOn::Axis,
            }),
            guaranteed: None,
            design: &design,
            identified: None,
            controller_file: "controller.toml",
        }));
        r.provenance = Some(crate::record::provenance::Provenance::now(
            vec!["beltune".into(), "commission".into()],
            Some(3),
        ));
        let html = render_html(&r).unwrap();
        assert!(html.contains("axis &lt;1&gt;"));
        assert!(
            html.contains("id=\"verdict-result\" class=\"fail\">FAIL<"),
            "2 mm fails"
        );
        assert!(html.contains("@media print"));
        assert!(html.contains("<code>beltune commission</code>"));
        assert!(html.contains("<svg"));
        assert!(!html.contains("http://") || html.contains("xmlns=\"http://www.w3.org/2000/svg\""));
        // no network: the only addresses are the SVG namespace and uPlot's
        // provenance in comments
        let urls = html.matches("http").count();
        let allowed = html.matches("http://www.w3.org/2000/svg").count()
            + html.matches("https://github.com/leeoniya/uPlot").count();
        assert_eq!(urls, allowed, "a network address in the report");
        assert!(
            !html.contains(" src="),
            "a script or image loaded from elsewhere"
        );
    }

    /// A figure with an interactive chart carries its SVG (for print and
    /// browsers without scripts) and the chart's data; the page inlines
    /// uPlot and needs no network.
    #[test]
    fn a_figure_with_a_chart_keeps_its_svg_and_inlines_the_chart() {
        let design = crate::design::design(
            &crate::design::DesignInput::new(crate::model::TwoMassParams::thesis_table_a4(), 1e-3),
            &crate::design::DesignKnobs::default(),
        )
        .unwrap();
        let loops = crate::report::bode::loop_plots(&design, 10.0, 30.0).unwrap();
        let r = Report {
            title: "t".into(),
            controller: Some(loops.controller),
            ..Default::default()
        };
        let html = render_html(&r).unwrap();
        let fig = html
            .split("<figure id=\"controller\">")
            .nth(1)
            .expect("the controller figure")
            .split("</figure>")
            .next()
            .unwrap();
        assert!(
            fig.contains("<div class=\"static has-chart\"><svg"),
            "{}",
            &fig[..200]
        );
        assert!(fig.contains("<div class=\"interactive\"></div>"));
        let data = html
            .split("<script type=\"application/json\" id=\"chart-data\">")
            .nth(1)
            .unwrap()
            .split("</script>")
            .next()
            .unwrap();
        let charts: serde_json::Value = serde_json::from_str(data).unwrap();
        assert_eq!(charts[0]["figure_id"], "controller");
        assert_eq!(charts[0]["panels"][0]["xlog"], true);
        assert!(html.contains(&format!("(v{})", web::UPLOT_VERSION)));
        assert!(
            html.contains("Permission is hereby granted"),
            "uPlot's licence"
        );
        let urls = html.matches("http").count();
        let allowed = html.matches("http://www.w3.org/2000/svg").count()
            + html.matches("https://github.com/leeoniya/uPlot").count();
        assert_eq!(urls, allowed, "a network address in the report");
        assert!(!html.contains(" src="));
    }
}
