//! Numbers for people: fitted values with symbol, display unit and a sensible number of
//! digits ("τ = 17.50 ± 0.01 ms", "β = 0.59 GPa"), the active model effects, and the
//! optimiser's stop reason in words.

pub use crate::format::{compact, value_pm};
use crate::identify::refine::REFINEMENTS;
use crate::params::Params;

/// Symbol, display scale (display = SI × scale), unit of a fitted parameter by its report
/// name (`tau_s`, `effective_bulk_modulus_pa`, …). Unknown names pass through unchanged.
pub fn display_of(name: &str) -> (&str, f64, &'static str) {
    match crate::identify::units::display_unit(name) {
        ("", _, _) => (name, 1.0, ""),
        known => known,
    }
}

/// "τ = 17.50 ± 0.01 ms" for a fitted parameter given in SI by its report name.
pub fn fitted(name: &str, value_si: f64, std_si: f64) -> String {
    let (sym, scale, unit) = display_of(name);
    let s = value_pm(value_si * scale, std_si * scale);
    if unit.is_empty() {
        format!("{sym} = {s}")
    } else {
        format!("{sym} = {s} {unit}")
    }
}

/// A controller for people: its structure and every gain it reads, by symbol in display
/// units, e.g. `paper (Kp = −5 V/m, Ki = −7.5 V·s/m)` (the parameter table's names, not the
/// preset keys).
pub fn controller_text(c: &crate::params::ControllerParams) -> String {
    let gains: Vec<String> = c
        .kind
        .keys()
        .iter()
        .filter_map(|k| {
            let v = c.get(k)?;
            Some(match crate::params::spec(&format!("controller.{k}")) {
                Some(s) if s.display.unit.is_empty() => {
                    format!("{} = {}", s.symbol, compact(s.to_display(v)))
                }
                Some(s) => format!(
                    "{} = {} {}",
                    s.symbol,
                    compact(s.to_display(v)),
                    s.display.unit
                ),
                None => format!("{k} = {}", compact(v)),
            })
        })
        .collect();
    format!("{} ({})", c.kind, gains.join(", "))
}

/// Rewrites every number in `text` that carries more than six significant digits
/// ("1.000365001548847e0", "80.871000") with four ("1", "80.87"); other text is kept.
pub fn shorten_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            let c = text[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
            continue;
        }
        let mut j = i;
        while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
            j += 1;
        }
        if j < b.len() && (b[j] == b'e' || b[j] == b'E') {
            let mut k = j + 1;
            if k < b.len() && (b[k] == b'-' || b[k] == b'+') {
                k += 1;
            }
            if k < b.len() && b[k].is_ascii_digit() {
                while k < b.len() && b[k].is_ascii_digit() {
                    k += 1;
                }
                j = k;
            }
        }
        let token = &text[i..j];
        let digits = token
            .split(['e', 'E'])
            .next()
            .unwrap_or("")
            .chars()
            .filter(|c| c.is_ascii_digit())
            .collect::<String>();
        let significant = digits.trim_start_matches('0').len();
        match token.parse::<f64>() {
            // Four significant digits, trailing zeros kept ("1.000" says it is not exactly 1).
            Ok(v) if significant > 6 => out.push_str(&value_pm(v, f64::NAN)),
            Ok(v) if token.contains(['e', 'E']) => out.push_str(&compact(v)),
            _ => out.push_str(token),
        }
        i = j;
    }
    out
}

/// An effect for [`active_effects`]: whether it is on, its name, and its main values by
/// parameter key.
type EffectLine<'a> = (bool, &'a str, &'a [(&'a str, f64)]);

/// The model effects switched on in `p`, each with its main values, for people
/// ("friction (F_c = 12.30 N, b = 150.0 N·s/m)"). Empty when none is on.
pub fn active_effects(p: &Params) -> Vec<String> {
    let e = &p.plant.effects;
    let effects: [EffectLine<'_>; 6] = [
        (
            e.friction.enabled,
            "friction",
            &[
                ("coulomb_n", e.friction.coulomb_n),
                ("viscous_n_s_per_m", e.friction.viscous_n_s_per_m),
                ("stribeck_n", e.friction.stribeck_n),
            ],
        ),
        (
            e.valve_overlap.enabled,
            "valve overlap",
            &[
                ("overlap_m", e.valve_overlap.overlap_m),
                ("edge_width_m", e.valve_overlap.edge_width_m),
            ],
        ),
        (
            e.valve_offset.enabled,
            "valve offset",
            &[("bias_v", e.valve_offset.bias_v)],
        ),
        (
            e.leakage.enabled,
            "leakage",
            &[
                ("coefficient_m3_per_s_pa", e.leakage.coefficient_m3_per_s_pa),
                ("growth_per_pa", e.leakage.growth_per_pa),
            ],
        ),
        (
            e.compliance.enabled,
            "compliance",
            &[
                (
                    "effective_bulk_modulus_pa",
                    e.compliance.effective_bulk_modulus_pa,
                ),
                ("hose_bulk_modulus_pa", e.compliance.hose_bulk_modulus_pa),
            ],
        ),
        (
            e.supply_sag.enabled,
            "supply sag",
            &[("droop_pa_per_m3_s", e.supply_sag.droop_pa_per_m3_s)],
        ),
    ];
    effects
        .iter()
        .filter(|(on, ..)| *on)
        .map(|(_, name, values)| {
            // A refinement of an effect's law at 0 is its plain law (hoses as the chambers, a
            // fixed gap): unsaid.
            let refinement = |key: &str| REFINEMENTS.iter().any(|k| k.name() == key);
            let values: Vec<String> = values
                .iter()
                .filter(|(key, v)| !(*v == 0.0 && refinement(key)))
                .map(|(key, v)| fitted(key, *v, f64::NAN))
                .collect();
            format!("{name} ({})", values.join(", "))
        })
        .collect()
}
