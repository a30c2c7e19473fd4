//! The self-contained report page: inline SVG, inline CSS, no scripts, no network.

use super::data::Report;
use super::plot;
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
figure { margin: 0.5em 0; } figure svg { width: 100%; height: auto; }
pre { background: #f6f8fa; padding: 0.6em; font-size: 0.85em; overflow-x: auto; }
</style>
</head>
<body>
<h1>{{ title }}</h1>
<p class="summary">{{ summary }}</p>

<h2>Parameters</h2>
<table>
<tr><th>quantity</th><th>unit</th><th>before (data sheet / default)</th><th>after (commissioned)</th>{% if has_truth %}<th>simulation truth</th>{% endif %}</tr>
{% for p in parameters %}<tr><td>{{ p.name }}</td><td>{{ p.unit }}</td><td>{{ p.before or "" }}</td><td>{{ p.after }}</td>{% if has_truth %}<td>{{ p.truth or "" }}</td>{% endif %}</tr>
{% endfor %}</table>

{% if validation_rows %}<h2>Validation</h2>
<table>
<tr><th>feedforward</th><th>max cart tracking error</th><th>static error</th><th>settling time</th></tr>
{% for r in validation_rows %}<tr><td>{{ r[0] }}</td><td>{{ r[1] }}</td><td>{{ r[2] }}</td><td>{{ r[3] }}</td></tr>
{% endfor %}</table>{% endif %}

{% for fig in figures %}<h2>{{ fig.heading }}</h2>
<figure id="{{ fig.id }}">{{ fig.svg }}</figure>
{% endfor %}

<h2>Log</h2>
<pre>{% for line in log %}{{ line }}
{% endfor %}</pre>
</body>
</html>
"#;

/// Render the report to one self-contained HTML page (every plot inline SVG).
pub fn render_html(report: &Report) -> Result<String> {
    let mut figures: Vec<Value> = Vec::new();
    let mut add = |id: &str, heading: &str, svg: String| {
        figures.push(context! {
            id => id,
            heading => heading,
            svg => Value::from_safe_string(svg),
        });
    };
    if let Some(frf) = &report.frf {
        add(
            "frf",
            "Measured frequency response, coherence and fitted model",
            plot::frf_svg(frf)?,
        );
    }
    if let Some(c) = &report.controller {
        add("controller", "Controller", plot::bode_svg(c)?);
    }
    for (i, ol) in report.open_loops.iter().enumerate() {
        add(&format!("open-loop-{i}"), &ol.title, plot::bode_svg(ol)?);
    }
    if let Some(f) = &report.friction {
        add("friction", "Friction", plot::friction_svg(f)?);
    }
    if !report.moves.is_empty() {
        add("moves", "Validation moves", plot::moves_svg(&report.moves)?);
    }
    let mut env = Environment::new();
    env.add_template("report.html", TEMPLATE)
        .map_err(|e| Error::Report {
            reason: e.to_string(),
        })?;
    let tmpl = env.get_template("report.html").map_err(|e| Error::Report {
        reason: e.to_string(),
    })?;
    tmpl.render(context! {
        title => &report.title,
        summary => &report.summary,
        parameters => Value::from(Serde(&report.parameters)),
        has_truth => report.parameters.iter().any(|p| p.truth.is_some()),
        validation_rows => Value::from(Serde(&report.validation_rows)),
        figures => figures,
        log => Value::from(Serde(&report.log)),
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
            }],
            friction: Some(FrictionPlot {
                velocity_rad_s: vec![-10.0, 10.0],
                torque_nm: vec![-0.15, 0.15],
                viscous_nm_s_per_rad: 2.5e-3,
                coulomb_nm: 0.125,
            }),
            ..Default::default()
        };
        let html = render_html(&r).unwrap();
        assert!(html.contains("axis &lt;1&gt;"));
        assert!(html.contains("<svg"));
        assert!(!html.contains("http://") || html.contains("xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(!html.contains("<script"));
    }
}
