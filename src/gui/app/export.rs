//! What the app exports: the live traces as a CSV table and the plots as figures.

use super::*;

impl SeatTwinApp {
    /// The traces in the window as a CSV table (SI, the dataset format; twin columns carry
    /// the dataset's names so the file reads back as a measured record).
    pub fn traces_table(&self) -> CsvTable {
        let header = vec![
            "t",
            "x",
            "xdd",
            "u",
            "du",
            "ydd",
            "v_in",
            "xv",
            "p1",
            "p2",
            "q1",
            "q2",
            "contact",
            "linear_u",
            "linear_ydd",
            "linear_v_in",
            "passive_u",
            "passive_ydd",
        ];
        let rows = self
            .traces
            .rows()
            .iter()
            .map(|r| {
                let (w, l, p) = (&r.twin, &r.linear, &r.passive);
                vec![
                    r.t,
                    w.x,
                    w.xdd,
                    w.u,
                    w.du,
                    w.ydd,
                    w.v_in,
                    w.xv,
                    w.p1,
                    w.p2,
                    w.q1,
                    w.q2,
                    f64::from(u8::from(w.contact)),
                    l.u,
                    l.ydd,
                    l.v_in,
                    p.u,
                    p.ydd,
                ]
            })
            .filter(|row| row.iter().all(|v| v.is_finite()))
            .collect();
        let c = &self.params.controller;
        let mut comments = vec![
            (
                "source".into(),
                "seat-twin live traces (twin, linear, passive)".into(),
            ),
            ("preset".into(), self.preset.name.clone()),
            ("controller".into(), c.kind.name().to_string()),
            ("kp_v_per_m".into(), c.kp_v_per_m.to_string()),
            ("ki_v_s_per_m".into(), c.ki_v_s_per_m.to_string()),
            (
                "units".into(),
                "SI (s, m, m/s², V, Pa, m³/s); t continues across restarts".into(),
            ),
        ];
        // Every parameter that made the traces (the preset's keys, SI), so the file says
        // what ran: lead, τ and the plant as well as the two gains above (other controller
        // kinds' gains are left out: they were not used).
        for spec in crate::params::PARAMS
            .iter()
            .filter(|s| s.applies_to(c.kind))
            .filter(|s| !matches!(s.key, "controller.kp_v_per_m" | "controller.ki_v_s_per_m"))
        {
            comments.push((
                spec.key.to_string(),
                format!("{} {}", spec.get(&self.params), spec.unit),
            ));
        }
        CsvTable {
            header,
            comments,
            rows,
        }
    }

    /// The four frequency plots as a report figure, with what the view shows: the same curve
    /// names and colours, the A/B reference, the dwell points on every plot where the view
    /// draws them (current and stable only), the phase wrapped or unwrapped as in the view,
    /// and no curve the legend has hidden. An unstable loop says so in the title.
    fn frequency_figure(&self) -> Figure {
        use crate::gui::frequency::{dwell_shown, freq_panels, shown_phase};
        let c = self.centre.curves();
        let unwrapped = self.settings.phase_unwrapped;
        let unstable = c.unstable();
        // Dark markers on the figure's white ground (the view's are the theme's strongest
        // text colour).
        let dwell_c = dwell_shown(c, self.centre.dwell(), &self.params)
            .then_some(crate::gui::style::FIGURE_DWELL);
        let rgb = |c: egui::Color32| Rgb(c.r(), c.g(), c.b());
        // A curve as the view draws it: a phase wrapped into segments joined by a break.
        let points = |pts: &[egui_plot::PlotPoint], phase: bool| -> (Vec<f64>, Vec<f64>) {
            let segments = if phase {
                shown_phase(pts, unwrapped)
            } else {
                vec![pts.to_vec()]
            };
            let mut xy = (Vec::new(), Vec::new());
            for (i, seg) in segments.iter().enumerate() {
                if i > 0 {
                    xy.0.push(f64::NAN);
                    xy.1.push(f64::NAN);
                }
                for p in seg {
                    xy.0.push(10f64.powf(p.x));
                    xy.1.push(p.y);
                }
            }
            xy
        };
        let panels =
            freq_panels(c, self.centre.dwell(), self.ab.drawn_curves(), dwell_c).map(|fp| {
                let shown = |name: &str| {
                    !crate::gui::plotkit::hidden(self.centre.hidden_curves(), fp.id, name)
                };
                let title = match fp.id {
                    "t_mag" => "Transmissibility",
                    "bode_mag" => "Valve/actuator (du/dt)/V_in",
                    _ => "",
                };
                // The view's short axis title with the full unit.
                let y_label = if fp.phase {
                    fp.y_label.to_string()
                } else {
                    let base = fp.y_label.split(" [").next().unwrap_or(fp.y_label);
                    format!("{base} [{}]", fp.unit)
                };
                let mut p = Panel::new(title, "frequency [Hz]", y_label);
                p.x_scale = Scale::Log10;
                for (style, pts) in fp.lines.iter().filter(|(s, _)| shown(s.name)) {
                    let (x, y) = points(pts, fp.phase);
                    p.series.push(styled(
                        Series::line(style.name, x, y, rgb(style.color)),
                        style.width,
                        style.style,
                    ));
                }
                if let Some((name, color, pts)) = fp.dwell.filter(|(n, ..)| shown(n))
                    && !pts.is_empty()
                {
                    let (x, y) = points(pts, fp.phase);
                    p.series.push(Series::markers(name, x, y, rgb(color)));
                }
                if fp.id == "t_mag" {
                    p.hlines = vec![(0.0, "|T| = 1".into())];
                    // As in the view: where |T| rises through 1 (the end of the isolation band)
                    // for the linear model and the twin, and the margins in the title; neither
                    // for an unstable loop, where they mean nothing.
                    if !unstable {
                        let who = [
                            ("linear", rgb(crate::gui::style::LINEAR)),
                            ("twin", rgb(crate::gui::style::TWIN)),
                        ];
                        for ((name, color), cs) in who.into_iter().zip(&c.crossings) {
                            if let Some(x) = cs.iter().find(|x| x.rising) {
                                p.series.push(Series::markers(
                                    format!("|T| = 1 @ {:.2} Hz ({name})", x.freq_hz),
                                    vec![x.freq_hz],
                                    vec![0.0],
                                    color,
                                ));
                            }
                        }
                        let margins: Vec<String> = ["linear", "twin"]
                            .iter()
                            .zip(&c.stability)
                            .filter_map(|(name, s)| {
                                s.as_ref().map(|s| {
                                    format!(
                                        "{name} {}",
                                        crate::gui::frequency::margin_text(&s.margins)
                                    )
                                })
                            })
                            .collect();
                        if !margins.is_empty() {
                            p.title = format!("{title} — {}", margins.join("; "));
                        }
                    }
                }
                p
            });
        let mut freq = Figure::new(
            format!(
                "seat-twin — preset {}{} — {}, {}{}",
                self.preset.name,
                if self.is_modified() {
                    " (modified)"
                } else {
                    ""
                },
                crate::gui::format::controller_text(&self.params.controller),
                delay_text(&self.params),
                if unstable {
                    " — UNSTABLE closed loop (not a steady state)"
                } else {
                    ""
                }
            ),
            panels.into(),
        );
        freq.height = 1200;
        freq
    }

    /// The current plots as report figures: frequency responses and scopes.
    pub fn plot_figures(&self) -> Vec<(&'static str, Figure)> {
        use crate::gui::frequency::REFERENCE_NAME;
        let freq = self.frequency_figure();
        use crate::gui::style::{self, CurveKind};
        let rgb = |c: Color32| Rgb(c.r(), c.g(), c.b());
        let (lin_c, twin_c, pas_c) = (rgb(style::LINEAR), rgb(style::TWIN), rgb(style::PASSIVE));
        let tr = &self.traces;
        // Each curve in the view's line style (dashed linear model and B, dotted passive),
        // so the figure still tells them apart where they overlap and in black and white.
        let ch_as = |label: &str, chan: Ch, color: Rgb, model: CurveKind| {
            let (x, y) = tr.channel(chan).points().iter().map(|p| (p.x, p.y)).unzip();
            let (w, st) = style::style_of(model);
            styled(Series::line(label, x, y, color), w, st)
        };
        let ch = |label: &str, chan: Ch, color: Rgb| {
            let model = match label {
                "linear" => CurveKind::Linear,
                "passive" => CurveKind::Passive,
                "platform" => CurveKind::Platform,
                "p2" | "Q2" => CurveKind::Second,
                l if l.starts_with("B") => CurveKind::Reference,
                _ => CurveKind::Twin,
            };
            ch_as(label, chan, color, model)
        };
        let mut acc = Panel::new("Live traces", "time [s]", "acceleration [m/s²]");
        acc.series = vec![
            ch("platform", Ch::PlatformAcc, rgb(style::PLATFORM)),
            ch("passive", Ch::PassiveAcc, pas_c),
            ch("linear", Ch::LinearAcc, lin_c),
            ch("twin", Ch::TwinAcc, twin_c),
        ];
        let mut stroke = Panel::new("", "time [s]", "stroke u [mm]");
        let lim = self.params.plant.cylinder.stroke_m / 2.0 * MM_PER_M;
        stroke.series = vec![
            ch("passive", Ch::PassiveU, pas_c),
            ch("linear", Ch::LinearU, lin_c),
            ch("twin", Ch::TwinU, twin_c),
        ];
        stroke.hlines = vec![(lim, "end stop".into()), (-lim, "end stop".into())];
        stroke.vspans = tr.contacts().to_vec();
        let mut pr = Panel::new("", "time [s]", "pressure [bar]");
        pr.series = vec![
            ch("p1", Ch::P1, rgb(style::P1)),
            ch("p2", Ch::P2, rgb(style::P2)),
        ];
        let mut q = Panel::new("", "time [s]", "flow [L/min]");
        q.series = vec![
            ch("Q1", Ch::Q1, rgb(style::P1)),
            ch("Q2", Ch::Q2, rgb(style::P2)),
        ];
        let mut v = Panel::new("", "time [s]", "V_in [V]");
        v.series = vec![
            ch("linear", Ch::LinearVin, lin_c),
            ch("twin", Ch::TwinVin, twin_c),
        ];
        if self.ab.is_on() {
            // The A/B reference twin (B), as the view overlays it.
            let b = rgb(style::REFERENCE);
            acc.series.push(ch(REFERENCE_NAME, Ch::RefAcc, b));
            stroke.series.push(ch("B: reference u", Ch::RefU, b));
            v.series.push(ch("B: reference V_in", Ch::RefVin, b));
        }
        let mut xv = Panel::new("", "time [s]", "spool x_v [mm]");
        xv.series = vec![ch("twin", Ch::TwinXv, twin_c)];
        let mut scopes = Figure::new(
            format!(
                "seat-twin — preset {}{} — {}, {} — live traces",
                self.preset.name,
                if self.is_modified() {
                    " (modified)"
                } else {
                    ""
                },
                crate::gui::format::controller_text(&self.params.controller),
                delay_text(&self.params),
            ),
            vec![acc, stroke, pr, q, v, xv],
        );
        scopes.height = 1500;
        vec![("frequency", freq), ("scopes", scopes)]
    }
}

/// `series` drawn as the view draws its curve: width `width` [px] and dashed unless
/// `style` is solid (the figure has one dash pattern for the view's dashes and dots).
fn styled(mut series: Series, width: f32, style: egui_plot::LineStyle) -> Series {
    if let crate::plot::SeriesStyle::Line {
        width: w, dashed, ..
    } = &mut series.style
    {
        *w = width.round().max(1.0) as u32;
        *dashed = !matches!(style, egui_plot::LineStyle::Solid);
    }
    series
}

/// The valve's delay for a figure title, in the display unit of the parameter table
/// ("τ = 17.5 ms").
fn delay_text(p: &Params) -> String {
    match crate::params::spec("valve.tau_s") {
        Some(s) => format!(
            "{} = {} {}",
            s.symbol,
            crate::gui::format::compact(s.to_display(s.get(p))),
            s.display.unit
        ),
        None => format!("τ = {} s", p.plant.valve.tau_s),
    }
}
