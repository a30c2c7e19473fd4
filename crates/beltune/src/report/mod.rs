//! The commissioning report: plain data in ([`data`]), SVG plots ([`plot`]),
//! one self-contained HTML page ([`html`]). Computation happens elsewhere;
//! this module only draws what it is given.

pub mod build;
pub mod compare;
pub mod data;
pub mod html;
pub mod plot;
pub mod plot_data;
pub mod verdict_old;

pub use data::{
    BodeCurve, BodePlot, ExcitationPlot, FrequencyMarker, FrfPlot, FrictionPlot, MarginPoint,
    MovePlot, Panel, ParameterRow, Report, Table,
};
pub use html::render_html;
