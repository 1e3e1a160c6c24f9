//! Fitted parameters for people: a parameter's symbol and display unit from the parameter
//! table, and its value with its uncertainty in that unit (the digits chosen by
//! [`crate::format`]). Used by the report, the drift summary, the CLI and the app.

use crate::format;

/// Display form of a fitted parameter by its report name (the last part of its preset key:
/// `cd`, `tau_s`, `coulomb_n`): `(symbol, scale from SI, unit)`, display = SI × scale, read
/// from the parameter table [`crate::params::PARAMS`] (the first key ending in the name, so
/// `tau_s` is the valve's delay); `("", 1, "")` for a name it does not know. Used by the
/// report, the CLI and the app.
pub fn display_unit(name: &str) -> (&'static str, f64, &'static str) {
    crate::params::PARAMS
        .iter()
        .find(|s| s.key.rsplit('.').next() == Some(name))
        .map_or(("", 1.0, ""), |s| {
            (s.symbol, s.display.scale, s.display.unit)
        })
}

/// `τ = 17.50 ± 0.01 ms`: the parameter in its display unit with its 1-σ uncertainty.
pub fn format_parameter(name: &str, value: f64, std: f64) -> String {
    let (sym, k, unit) = display_unit(name);
    let sym = if sym.is_empty() { name } else { sym };
    let (v, u) = (value * k, std * k.abs());
    let min_decimals = if v.abs() >= 100.0 { 0 } else { 2 };
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    let shown = format::uncertain(v, u, min_decimals);
    if u.is_finite() {
        format!("{sym} = {shown}{unit}")
    } else {
        format!("{sym} = {shown}{unit} (uncertainty not determined)")
    }
}

/// A parameter value alone in its display unit (`0.596 GPa`).
pub fn format_value(name: &str, value: f64) -> String {
    let (_, k, unit) = display_unit(name);
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!("{}{unit}", format::by_magnitude(value * k))
}
