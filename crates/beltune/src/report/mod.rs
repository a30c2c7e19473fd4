//! What a person reads, and the data behind it: the report of a result and
//! the comparison of two.
//!
//! | file | what |
//! | --- | --- |
//! | [`plot_data`] | the loops of a design and the measured FRF as plot data (also the tuning page's) |
//! | [`data_files`] | the CSV files beside the report: one writer and one reader each |
//! | [`bode`] | the Bode plots of a design: open loops with margins, closed loops, sensitivities |
//! | [`build`] | the report of a result, from its record and data files |
//! | [`folder`] | a result folder: read one, write one as a set |
//! | [`compare`] | two result folders side by side |
//! | [`data`] | what the page shows, as plain data |
//! | [`vendor`] | the controller in the parameter names and units of drive families' manuals |
//! | [`plot`], [`html`] | drawing: SVG plots, one self-contained HTML page |
//! | [`chart`], [`web`] | the interactive plots (uPlot) of the page and the report: their data, the vendored scripts |
//!
//! Computation of results happens upstream (`commission`, `verdict`); this
//! module only arranges and draws what it is given.

pub mod bode;
pub mod build;
pub mod chart;
pub mod compare;
pub mod data;
pub mod data_files;
pub mod folder;
pub mod health;
pub mod html;
pub mod plot;
pub mod plot_data;
pub mod vendor;
pub mod web;

pub use data::{
    BodeCurve, BodePlot, ExcitationPlot, FrequencyMarker, FrfPlot, FrictionPlot, MarginPoint,
    MovePlot, Panel, ParameterRow, Report, Table, TrendPlot,
};
pub use html::render_html;
