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

/// Text of an error or a refusal.
pub const ERROR_TEXT: Color32 = Color32::from_rgb(220, 50, 40);
/// Text of something that went well (a lesson step done, a residual within its limit,
/// the engine running).
pub const OK_TEXT: Color32 = Color32::from_rgb(40, 160, 60);
/// Text of a caution (a residual above its limit, an unexplained misfit).
pub const CAUTION_TEXT: Color32 = Color32::from_rgb(220, 120, 20);
/// Text of a thin margin or a state outside the model.
pub const WARNING_TEXT: Color32 = Color32::from_rgb(230, 150, 20);
/// Text of a neutral finding (no missing effect).
pub const NEUTRAL_TEXT: Color32 = Color32::from_rgb(40, 120, 200);
/// Text of a failed job step (diverged dwell points, failed Tune rides).
pub const FAILED_TEXT: Color32 = Color32::from_rgb(200, 60, 40);
/// Text of too little data to judge.
pub const INSUFFICIENT_TEXT: Color32 = Color32::from_rgb(200, 60, 60);
/// Ground of the unstable-loop banner (white text on it).
pub const UNSTABLE_FILL: Color32 = Color32::from_rgb(180, 30, 30);

/// The end stops and the contacts with them, in the scopes.
pub const END_STOP: Color32 = Color32::from_rgb(200, 30, 30);
/// The ground of an end-stop contact span in the scopes.
pub const CONTACT_FILL: Color32 = Color32::from_rgba_premultiplied(200, 30, 30, 60);
/// The vertical line where the parameters changed (the metrics restart there).
pub const CHANGE_MARK: Color32 = Color32::from_gray(140);
/// Dark markers of the dwell points on an exported figure's white ground (the view's are
/// the theme's strongest text colour).
pub const FIGURE_DWELL: Color32 = Color32::from_rgb(30, 30, 30);

/// A measured channel (measured-data window).
pub const MEASURED: Color32 = Color32::from_rgb(150, 150, 150);
/// The calibrated twin's replay (measured-data window).
pub const CALIBRATED: Color32 = Color32::from_rgb(44, 160, 44);
/// The residual, measured − replayed (measured-data window).
pub const RESIDUAL: Color32 = Color32::from_rgb(214, 39, 40);

/// Guide lines drawn over the curves (|T| = 1, the end stops): dashed.
pub fn guide_style() -> LineStyle {
    LineStyle::dashed_dense()
}

/// Marks on the time or frequency axis (a parameter change, a |T| = 1 crossing): dotted.
pub fn mark_style() -> LineStyle {
    LineStyle::dotted_dense()
}

/// How the frequency plots draw each model: a little wider than in the scopes (fewer,
/// smoother curves). `(width [points], style)`; the reference as in [`style_of`].
pub fn frequency_style_of(kind: CurveKind) -> (f32, LineStyle) {
    match kind {
        CurveKind::Twin => (2.4, LineStyle::Solid),
        CurveKind::Linear => (1.8, LineStyle::dashed_dense()),
        other => style_of(other),
    }
}

/// The rig schematic's colours.
pub mod rig {
    use egui::Color32;

    /// Chamber pressure at the low end of the scale.
    pub const PRESSURE_LOW: Color32 = Color32::from_rgb(40, 90, 200);
    /// Chamber pressure in the middle of the scale.
    pub const PRESSURE_MID: Color32 = Color32::from_rgb(235, 235, 235);
    /// Chamber pressure at the high end of the scale.
    pub const PRESSURE_HIGH: Color32 = Color32::from_rgb(210, 40, 30);
    /// Steel (cylinder walls, frame) on a dark theme.
    pub const STEEL_DARK_THEME: Color32 = Color32::from_gray(120);
    /// Steel on a light theme.
    pub const STEEL_LIGHT_THEME: Color32 = Color32::from_gray(150);
    /// The piston.
    pub const PISTON: Color32 = Color32::from_gray(60);
    /// The piston rod.
    pub const ROD: Color32 = Color32::from_gray(90);
    /// The outline of a cylinder at its end stop.
    pub const CONTACT: Color32 = Color32::from_rgb(230, 30, 30);
    /// The springs.
    pub const SPRING: Color32 = Color32::from_rgb(90, 140, 90);
    /// The seat.
    pub const SEAT: Color32 = Color32::from_rgb(60, 60, 70);
    /// The valve body.
    pub const VALVE_BODY: Color32 = Color32::from_gray(70);
    /// The valve spool.
    pub const VALVE_SPOOL: Color32 = Color32::from_gray(40);
}
