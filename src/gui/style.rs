//! Colours and line styles of every curve in the app, in one place: the scopes, the
//! frequency plots, the Tune panel, the measured-data views and the exported figures all read
//! them from here.

use egui::Color32;
use egui_plot::LineStyle;

/// The twin's colour.
pub const TWIN: Color32 = Color32::from_rgb(31, 119, 180);
/// Linear model colour.
pub const LINEAR: Color32 = Color32::from_rgb(255, 127, 14);
/// Passive model colour.
pub const PASSIVE: Color32 = Color32::from_rgb(44, 160, 44);
/// Platform colour.
pub const PLATFORM: Color32 = Color32::from_rgb(127, 127, 127);
/// Colour of the A/B reference twin (B) wherever it is drawn.
pub const REFERENCE: Color32 = Color32::from_rgb(220, 0, 150);
/// Upper chamber colour.
pub const P1: Color32 = Color32::from_rgb(214, 39, 40);
/// Lower chamber colour.
pub const P2: Color32 = Color32::from_rgb(148, 103, 189);

/// What a curve shows, for its line style.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveKind {
    /// The twin (solid, wide).
    Twin,
    /// The linear model (dashed).
    Linear,
    /// The passive reference (dotted).
    Passive,
    /// The platform (thin).
    Platform,
    /// The second of two twin channels in one scope (Q2 under Q1, p2 under p1): dashed.
    Second,
    /// The A/B reference twin (B): loosely dashed, magenta.
    Reference,
}

/// How each kind of curve is drawn wherever curves overlap: the twin solid and wider, the
/// linear model dashed on top of it, the passive reference dotted, the platform thin.
/// `(width [points], style)`.
pub fn style_of(kind: CurveKind) -> (f32, LineStyle) {
    match kind {
        CurveKind::Twin => (2.2, LineStyle::Solid),
        CurveKind::Linear => (1.6, LineStyle::dashed_dense()),
        CurveKind::Passive => (1.6, LineStyle::dotted_dense()),
        CurveKind::Platform => (1.0, LineStyle::Solid),
        CurveKind::Second => (1.6, LineStyle::dashed_dense()),
        CurveKind::Reference => (1.8, LineStyle::dashed_loose()),
    }
}

/// Ground of the banner of a stopped engine (white text on it).
pub const ENGINE_STOPPED_FILL: Color32 = Color32::from_rgb(150, 20, 20);
