//! The interactive plots of the tuning page and the reports: uPlot (MIT,
//! vendored unmodified in `assets/uplot/` with its licence, version and
//! provenance in `assets/uplot/README.md`) and beltune's drawing code on top
//! of it (`assets/plot/beltune-plot.js`: log frequency axes, zoom by dragging,
//! a read-out with units on hover, markers and reference lines). The page's
//! server serves these files; a report inlines them (no network).

/// uPlot's version (the git tag the files were taken from).
pub const UPLOT_VERSION: &str = "1.6.32";
/// uPlot, `dist/uPlot.iife.min.js` of [`UPLOT_VERSION`] (defines `window.uPlot`).
pub const UPLOT_JS: &str = include_str!("../../assets/uplot/uPlot.iife.min.js");
/// uPlot's style sheet, `dist/uPlot.min.css` of [`UPLOT_VERSION`].
pub const UPLOT_CSS: &str = include_str!("../../assets/uplot/uPlot.min.css");
/// uPlot's licence (MIT).
pub const UPLOT_LICENSE: &str = include_str!("../../assets/uplot/LICENSE");
/// beltune's plots on uPlot (defines `window.BeltunePlot`).
pub const PLOT_JS: &str = include_str!("../../assets/plot/beltune-plot.js");
/// The style of markers, reference lines and labels over the plots.
pub const PLOT_CSS: &str = include_str!("../../assets/plot/beltune-plot.css");

#[cfg(test)]
mod tests {
    use super::*;

    /// The vendored file is the version this module names (its banner says so).
    #[test]
    fn the_vendored_uplot_is_the_named_version() {
        assert!(
            UPLOT_JS.starts_with(&format!(
                "/*! https://github.com/leeoniya/uPlot (v{UPLOT_VERSION}) */"
            )),
            "{}",
            &UPLOT_JS[..80]
        );
        assert!(UPLOT_LICENSE.contains("The MIT License"));
        // inlined into a <script> element: must not end it early
        for s in [UPLOT_JS, PLOT_JS] {
            assert!(!s.to_ascii_lowercase().contains("</script"));
        }
    }
}
