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
        let comments = vec![
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
        CsvTable {
            header,
            comments,
            rows,
        }
    }

    /// The current plots as report figures: frequency responses and scopes.
    pub fn plot_figures(&self) -> Vec<(&'static str, Figure)> {
        let c = self.analytic.curves();
        let xy = |pts: &[egui_plot::PlotPoint], logx: bool| -> (Vec<f64>, Vec<f64>) {
            pts.iter()
                .map(|p| (if logx { 10f64.powf(p.x) } else { p.x }, p.y))
                .unzip()
        };
        let line = |label: &str, pts: &[egui_plot::PlotPoint], color: Rgb, logx: bool| {
            let (x, y) = xy(pts, logx);
            Series::line(label, x, y, color)
        };
        let (lin_c, twin_c, pas_c) = (Rgb(255, 127, 14), Rgb(31, 119, 180), Rgb(44, 160, 44));
        let mut t_mag = Panel::new("Transmissibility", "frequency [Hz]", "|T| [dB]");
        t_mag.x_scale = Scale::Log10;
        t_mag.series = vec![
            line("linear active", &c.t_mag[0], lin_c, true),
            line("twin active (linearised)", &c.t_mag[1], twin_c, true),
            line("passive", &c.t_mag[2], pas_c, true),
        ];
        if !self.dwell.mag.is_empty() {
            let (x, y) = xy(&self.dwell.mag, true);
            t_mag
                .series
                .push(Series::markers("twin simulated (dwell)", x, y, twin_c));
        }
        t_mag.hlines = vec![(0.0, "|T| = 1".into())];
        let mut t_ph = Panel::new("", "frequency [Hz]", "phase T [deg]");
        t_ph.x_scale = Scale::Log10;
        t_ph.series = vec![
            line("linear active", &c.t_phase[0], lin_c, true),
            line("twin active", &c.t_phase[1], twin_c, true),
            line("passive", &c.t_phase[2], pas_c, true),
        ];
        let mut b_mag = Panel::new(
            "Valve/actuator (du/dt)/V_in",
            "frequency [Hz]",
            "|du/dt / V_in| [dB re (mm/s)/V]",
        );
        b_mag.x_scale = Scale::Log10;
        b_mag.series = vec![
            line("twin (linearised)", &c.bode_mag[0], twin_c, true),
            line("G(s)", &c.bode_mag[1], lin_c, true),
        ];
        let mut b_ph = Panel::new("", "frequency [Hz]", "phase (du/dt)/V_in [deg]");
        b_ph.x_scale = Scale::Log10;
        b_ph.series = vec![
            line("twin (linearised)", &c.bode_phase[0], twin_c, true),
            line("G(s)", &c.bode_phase[1], lin_c, true),
        ];
        let mut freq = Figure::new(
            format!(
                "seat-twin — {} ({})",
                self.preset.name,
                crate::gui::format::controller_text(&self.params.controller)
            ),
            vec![t_mag, t_ph, b_mag, b_ph],
        );
        freq.height = 1200;

        let tr = &self.traces;
        let ch = |label: &str, chan: Ch, color: Rgb| {
            line(label, tr.channel(chan).points(), color, false)
        };
        let mut acc = Panel::new("Live traces", "time [s]", "acceleration [m/s²]");
        acc.series = vec![
            ch("platform", Ch::PlatformAcc, Rgb(127, 127, 127)),
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
            ch("p1", Ch::P1, Rgb(214, 39, 40)),
            ch("p2", Ch::P2, Rgb(148, 103, 189)),
        ];
        let mut q = Panel::new("", "time [s]", "flow [L/min]");
        q.series = vec![
            ch("Q1", Ch::Q1, Rgb(214, 39, 40)),
            ch("Q2", Ch::Q2, Rgb(148, 103, 189)),
        ];
        let mut v = Panel::new("", "time [s]", "V_in [V]");
        v.series = vec![
            ch("linear", Ch::LinearVin, lin_c),
            ch("twin", Ch::TwinVin, twin_c),
        ];
        let mut xv = Panel::new("", "time [s]", "spool x_v [mm]");
        xv.series = vec![ch("twin", Ch::TwinXv, twin_c)];
        let mut scopes = Figure::new(
            format!("seat-twin — {} live traces", self.preset.name),
            vec![acc, stroke, pr, q, v, xv],
        );
        scopes.height = 1500;
        vec![("frequency", freq), ("scopes", scopes)]
    }
}
