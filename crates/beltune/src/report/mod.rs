//! Plots and the HTML report (being written).
