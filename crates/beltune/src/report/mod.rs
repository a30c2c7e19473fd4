//! The commissioning report: plain data in ([`data`]), SVG plots ([`plot`]),
//! one self-contained HTML page ([`html`]). Computation happens elsewhere;
//! this module only draws what it is given.

pub mod data;
pub mod html;
pub mod plot;

pub use data::{
    BodeCurve, BodePlot, FrequencyMarker, FrfPlot, FrictionPlot, MovePlot, ParameterRow, Report,
};
pub use html::render_html;
