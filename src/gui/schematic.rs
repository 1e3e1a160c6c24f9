//! A live schematic of the rig, drawn with the painter: platform, double-rod cylinder with its
//! two chambers coloured by pressure, the valve spool, the springs and the seat, all moving
//! with the twin's latest sample (motion to scale).

use super::style::rig;
use super::units::{BAR_PER_PA, MM_PER_M};
use crate::params::Params;
use crate::simulation::Sample;
use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Shape, Stroke, pos2, vec2};

/// Smallest half-width of the colour scale \[Pa\]: a still rig does not flicker through the
/// whole scale on a few mbar of noise.
pub const MIN_HALF_SPAN_PA: f64 = 0.25e5;

/// The pressure range the colours span \[Pa\]: the range seen in the scopes' window (both
/// chambers), widened to at least ±[`MIN_HALF_SPAN_PA`] around its middle; the return and
/// supply pressures before anything was seen.
pub fn color_range(seen_pa: Option<(f64, f64)>, params: &Params) -> (f64, f64) {
    match seen_pa {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() && hi >= lo => {
            let mid = 0.5 * (lo + hi);
            let half = (0.5 * (hi - lo)).max(MIN_HALF_SPAN_PA);
            (mid - half, mid + half)
        }
        _ => (
            params.plant.supply.return_pressure_pa,
            params.plant.supply.supply_pressure_pa,
        ),
    }
}

/// Colour of a pressure on the scale `range` \[Pa\]: blue at its low end, white in the
/// middle, red at its high end.
pub fn pressure_color(p_pa: f64, range: (f64, f64)) -> Color32 {
    let (lo, hi) = range;
    let t = if p_pa.is_finite() && hi > lo {
        ((p_pa - lo) / (hi - lo)).clamp(0.0, 1.0) as f32
    } else {
        0.5
    };
    let (low, mid, high) = (rig::PRESSURE_LOW, rig::PRESSURE_MID, rig::PRESSURE_HIGH);
    if t < 0.5 {
        low.lerp_to_gamma(mid, t * 2.0)
    } else {
        mid.lerp_to_gamma(high, (t - 0.5) * 2.0)
    }
}

/// Maps rig coordinates [mm] (origin bottom centre, y up) to the screen.
struct Frame {
    origin: Pos2,
    scale: f32,
}

impl Frame {
    fn p(&self, x_mm: f64, y_mm: f64) -> Pos2 {
        pos2(
            self.origin.x + x_mm as f32 * self.scale,
            self.origin.y - y_mm as f32 * self.scale,
        )
    }
    fn rect(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> Rect {
        Rect::from_two_pos(self.p(x0, y0), self.p(x1, y1))
    }
}

fn spring(f: &Frame, x: f64, y0: f64, y1: f64, stroke: Stroke) -> Shape {
    let turns = 7;
    let n = turns * 2;
    let mut pts = vec![f.p(x, y0)];
    let (a, b) = (y0 + 6.0, y1 - 6.0);
    pts.push(f.p(x, a));
    for i in 1..n {
        let y = a + (b - a) * i as f64 / n as f64;
        let dx = if i % 2 == 0 { -12.0 } else { 12.0 };
        pts.push(f.p(x + dx, y));
    }
    pts.push(f.p(x, b));
    pts.push(f.p(x, y1));
    Shape::line(pts, stroke)
}

/// Draws the rig for the sample `s` (the twin's) into the available space.
/// `seen_pa` is the pressure range seen in the scopes (both chambers), for the colour scale.
pub fn schematic_ui(
    ui: &mut egui::Ui,
    s: Option<&Sample>,
    params: &Params,
    height: f32,
    seen_pa: Option<(f64, f64)>,
) {
    let range = color_range(seen_pa, params);
    let width = ui.available_width();
    let (response, painter) = ui.allocate_painter(vec2(width, height), Sense::hover());
    let rect = response.rect;
    let visuals = ui.visuals();
    let ink = visuals.text_color();
    let steel = if visuals.dark_mode {
        rig::STEEL_DARK_THEME
    } else {
        rig::STEEL_LIGHT_THEME
    };
    painter.rect_filled(rect, 4.0, visuals.extreme_bg_color);

    let rest = Sample {
        t: 0.0,
        x: 0.0,
        xd: 0.0,
        xdd: 0.0,
        u: 0.0,
        du: 0.0,
        ydd: 0.0,
        v_in: 0.0,
        xv: 0.0,
        p1: 0.5 * (params.plant.supply.supply_pressure_pa + params.plant.supply.return_pressure_pa),
        p2: 0.5 * (params.plant.supply.supply_pressure_pa + params.plant.supply.return_pressure_pa),
        q1: 0.0,
        q2: 0.0,
        contact: false,
    };
    let s = s.copied().unwrap_or(rest);
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    let half = params.plant.cylinder.stroke_m / 2.0 * MM_PER_M;
    let x_mm = (finite(s.x) * MM_PER_M).clamp(-45.0, 45.0);
    let u_mm = (finite(s.u) * MM_PER_M).clamp(-half - 3.0, half + 3.0);
    let xv_rel = (finite(s.xv) / params.plant.valve.xv_max_m).clamp(-1.0, 1.0);

    // Rig extent: x −120…215 mm, y 0…(300 + 2·half) mm.
    let extent_w = 335.0_f32;
    let extent_h = 230.0 + 2.0 * half as f32 + 50.0;
    let scale = ((rect.width() - 16.0) / extent_w).min((rect.height() - 80.0) / extent_h);
    let f = Frame {
        origin: pos2(
            rect.center().x - (215.0 - 120.0) / 2.0 * scale,
            rect.bottom() - 8.0,
        ),
        scale,
    };
    let thin = Stroke::new(1.0, ink);

    // Ground and the shaker under the platform.
    painter.rect_filled(f.rect(-120.0, 0.0, 120.0, 8.0), 0.0, steel);
    for i in 0..12 {
        let x = -115.0 + 20.0 * i as f64;
        painter.line_segment([f.p(x, 0.0), f.p(x + 8.0, 8.0)], thin);
    }
    let plat0 = 50.0 + x_mm;
    painter.rect_filled(
        f.rect(-20.0, 8.0, 20.0, plat0 - 10.0),
        0.0,
        steel.gamma_multiply(0.6),
    );
    // Platform.
    painter.rect(
        f.rect(-110.0, plat0 - 10.0, 110.0, plat0),
        2.0,
        steel,
        thin,
        egui::StrokeKind::Inside,
    );
    // Cylinder: caps 10 mm, cavity 2·half + 10 (piston 10 mm).
    let cyl_h = 2.0 * half + 30.0;
    let cav0 = plat0 + 10.0;
    let cav1 = plat0 + cyl_h - 10.0;
    let mid = 0.5 * (cav0 + cav1);
    let piston = mid + u_mm;
    let (pl, pu) = ((piston - 5.0).max(cav0), (piston + 5.0).min(cav1));
    painter.rect_filled(f.rect(-32.0, plat0, 32.0, plat0 + cyl_h), 2.0, steel);
    painter.rect_filled(
        f.rect(-26.0, cav0, 26.0, pl),
        0.0,
        pressure_color(s.p2, range),
    );
    painter.rect_filled(
        f.rect(-26.0, pu, 26.0, cav1),
        0.0,
        pressure_color(s.p1, range),
    );
    painter.rect_filled(f.rect(-26.0, pl, 26.0, pu), 0.0, rig::PISTON);
    // Double rod: up to the seat plate, down through the bottom cap.
    let seat0 = plat0 + cyl_h + 20.0 + u_mm;
    painter.rect_filled(f.rect(-4.0, pu, 4.0, seat0), 0.0, rig::ROD);
    painter.rect_filled(
        f.rect(-4.0, (pl - half - 5.0).max(plat0 - 8.0), 4.0, pl),
        0.0,
        rig::ROD,
    );
    let label = |pos: Pos2, text: String, align: Align2| {
        painter.text(pos, align, text, FontId::proportional(11.0), ink);
    };
    // Readout in the top-left corner, colour-keyed like the drawing.
    let lines = [
        (format!("platform x {x_mm:+6.1} mm"), ink),
        (format!("stroke u   {u_mm:+6.1} mm"), ink),
        (
            format!("p1 (upper) {:6.1} bar", s.p1 * BAR_PER_PA),
            pressure_color(s.p1, range),
        ),
        (
            format!("p2 (lower) {:6.1} bar", s.p2 * BAR_PER_PA),
            pressure_color(s.p2, range),
        ),
    ];
    painter.text(
        rect.left_top() + vec2(22.0, 6.0 + 15.0 * 4.0),
        Align2::LEFT_TOP,
        format!(
            "colours: {:.1} … {:.1} bar",
            range.0 * BAR_PER_PA,
            range.1 * BAR_PER_PA
        ),
        FontId::proportional(10.0),
        visuals.weak_text_color(),
    );
    for (i, (text, color)) in lines.into_iter().enumerate() {
        let pos = rect.left_top() + vec2(8.0, 6.0 + 15.0 * i as f32);
        // The pressure lines carry a colour swatch and ink text; the others their colour.
        let text_color = if i >= 2 {
            painter.rect_filled(
                Rect::from_min_size(pos + vec2(0.0, 3.0), vec2(9.0, 9.0)),
                1.0,
                color,
            );
            ink
        } else {
            color
        };
        painter.text(
            pos + vec2(14.0, 0.0),
            Align2::LEFT_TOP,
            text,
            FontId::monospace(11.0),
            text_color,
        );
    }
    if s.contact {
        painter.rect_stroke(
            f.rect(-34.0, plat0 - 2.0, 34.0, plat0 + cyl_h + 2.0),
            2.0,
            Stroke::new(3.0, rig::CONTACT),
            egui::StrokeKind::Outside,
        );
        label(
            f.p(0.0, plat0 + cyl_h + 6.0),
            "END STOP".into(),
            Align2::CENTER_BOTTOM,
        );
    }

    // Springs between platform and seat plate.
    let spring_stroke = Stroke::new(2.0, rig::SPRING);
    for x in [-85.0, 85.0] {
        painter.add(spring(&f, x, plat0, seat0, spring_stroke));
    }

    // Seat plate and seat.
    painter.rect(
        f.rect(-105.0, seat0, 105.0, seat0 + 10.0),
        2.0,
        steel,
        thin,
        egui::StrokeKind::Inside,
    );
    let seat_color = rig::SEAT;
    painter.rect_filled(
        f.rect(-70.0, seat0 + 10.0, 70.0, seat0 + 35.0),
        6.0,
        seat_color,
    );
    painter.rect_filled(
        f.rect(-70.0, seat0 + 30.0, -50.0, seat0 + 120.0),
        6.0,
        seat_color,
    );
    label(
        f.p(75.0, seat0 + 22.0),
        format!("m = {:.1} kg", params.plant.body.mass_kg),
        Align2::LEFT_CENTER,
    );

    // Valve on the platform: body, spool (lands) shifted by x_v, hoses to the ports.
    let (v0, v1) = (plat0 + 20.0, plat0 + 50.0);
    let (vx0, vx1) = (120.0, 200.0);
    painter.rect(
        f.rect(vx0, v0, vx1, v1),
        2.0,
        visuals.faint_bg_color,
        thin,
        egui::StrokeKind::Inside,
    );
    let sx = 160.0 + 16.0 * xv_rel;
    painter.rect_filled(
        f.rect(sx - 30.0, v0 + 8.0, sx + 30.0, v1 - 8.0),
        1.0,
        rig::VALVE_BODY,
    );
    for dx in [-22.0, 0.0, 22.0] {
        painter.rect_filled(
            f.rect(sx + dx - 5.0, v0 + 4.0, sx + dx + 5.0, v1 - 4.0),
            1.0,
            rig::VALVE_SPOOL,
        );
    }
    // Two short lines above the valve body, right of the hose risers (which run at
    // x < vx0): "spool x_v" on one line, the value on the next.
    label(
        f.p(vx1, v1 + 3.0),
        format!("spool x_v\n{:+.3} mm", s.xv * MM_PER_M),
        Align2::RIGHT_BOTTOM,
    );
    label(f.p(140.0, v0 - 3.0), "P".into(), Align2::CENTER_TOP);
    label(f.p(180.0, v0 - 3.0), "T".into(), Align2::CENTER_TOP);
    let hose = |y_port: f64, y_valve: f64, p: f64| {
        let c = pressure_color(p, range);
        painter.add(Shape::line(
            vec![
                f.p(32.0, y_port),
                f.p(70.0 + (y_valve - v0), y_port),
                f.p(70.0 + (y_valve - v0), y_valve),
                f.p(vx0, y_valve),
            ],
            Stroke::new(4.0, c),
        ));
    };
    hose(cav1 - 4.0, v1 - 6.0, s.p1);
    hose(cav0 + 4.0, v0 + 6.0, s.p2);
}
