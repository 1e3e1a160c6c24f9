//! The FMU of the twin: its variables, `modelDescription.xml`, and the archive
//! (`seat-twin export fmu`, and File → Export FMU… in the app through [`write`](fn@write)).
//!
//! An FMI 2.0 co-simulation FMU, `modelIdentifier` `seat_twin`:
//!
//! ```text
//! seat_twin.fmu
//! ├── modelDescription.xml
//! ├── binaries/linux64/seat_twin.so     this crate's cdylib (the FMI 2.0 functions of
//! │                                     crate::export::fmi2, the engine behind them)
//! └── resources/preset.toml             the preset the FMU starts from
//!     resources/controller              `internal` or `external`
//! ```
//!
//! Variable names are the CSV column names of `seat-twin simulate`; parameters are the
//! preset's dotted keys, taken with unit, range and description from
//! [`crate::params::PARAMS`]. The controller gains are `tunable`; every other parameter is
//! `fixed` (settable before initialisation only).

use crate::params::{PARAMS, ParamSpec, Params};
use crate::preset::Preset;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The FMU's `modelIdentifier`: the shared library is `binaries/linux64/seat_twin.so`.
pub const MODEL_IDENTIFIER: &str = "seat_twin";

/// Where the valve command comes from inside the FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ControllerPlacement {
    /// The preset's controller runs inside, at the internal step (the closed loop `simulate`
    /// runs).
    #[default]
    Internal,
    /// The importer sends the command through the input `v_in_ext` (held between
    /// communication points, saturated and delayed by the valve as the internal one is).
    External,
}

impl ControllerPlacement {
    /// `internal` or `external` (the CLI's value and the resource file's content).
    pub fn name(self) -> &'static str {
        match self {
            ControllerPlacement::Internal => "internal",
            ControllerPlacement::External => "external",
        }
    }

    /// The placement named `s` (`internal`, `external`).
    pub fn from_name(s: &str) -> Option<Self> {
        match s.trim() {
            "internal" => Some(Self::Internal),
            "external" => Some(Self::External),
            _ => None,
        }
    }
}

/// What a variable is to the importer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set by the importer at communication points.
    Input,
    /// Computed by the FMU.
    Output,
    /// A parameter: `tunable` when it may change during the run, else `fixed`.
    Parameter {
        /// May be set between steps.
        tunable: bool,
    },
}

/// An FMU variable.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Value reference.
    pub vr: u32,
    /// Name (a CSV column name or a preset key).
    pub name: String,
    /// Input, output or parameter.
    pub causality: Causality,
    /// SI unit as written in the parameter table (`"-"` for none).
    pub unit: &'static str,
    /// What it is.
    pub description: String,
    /// Start value \[SI\] (inputs and parameters).
    pub start: Option<f64>,
    /// Valid range \[SI\], checked when set.
    pub range: Option<(f64, f64)>,
}

/// Value references of the outputs, in the order of [`OUTPUTS`].
pub const VR_OUTPUTS: u32 = 0;
/// Value reference of the input `xdd`.
pub const VR_XDD: u32 = 100;
/// Value reference of the input `x`.
pub const VR_X: u32 = 101;
/// Value reference of the input `v_in_ext`.
pub const VR_V_IN_EXT: u32 = 102;
/// Value reference of the parameter `PARAMS[i]` is `VR_PARAMS + i`.
pub const VR_PARAMS: u32 = 1000;

/// Range of the platform-acceleration input [m/s²] (±100 g).
pub const XDD_RANGE: (f64, f64) = (-1000.0, 1000.0);
/// Range of the platform-position input \[m\].
pub const X_RANGE: (f64, f64) = (-100.0, 100.0);
/// Range of the external command \[V\] (the valve saturates it at ±Vmax).
pub const V_IN_EXT_RANGE: (f64, f64) = (-1000.0, 1000.0);

/// The outputs: name, SI unit, description.
pub const OUTPUTS: [(&str, &str, &str); 8] = [
    (
        "u",
        "m",
        "relative displacement u = y - x of the body over the platform (stroke from mid-position)",
    ),
    ("ydd", "m/s^2", "absolute body acceleration"),
    ("p1", "Pa", "upper chamber pressure"),
    ("p2", "Pa", "lower chamber pressure"),
    ("q1", "m^3/s", "hose-1 flow"),
    ("q2", "m^3/s", "hose-2 flow"),
    ("xv", "m", "spool position"),
    (
        "v_in",
        "V",
        "valve command as sent, saturated to +-Vmax, before the valve's pure delay",
    ),
];

/// Whether the table entry `spec` is a parameter of the FMU for `params` and `placement`:
/// every entry that applies to the preset's controller kind; no controller gains when the
/// controller is external.
pub fn exposes(spec: &ParamSpec, params: &Params, placement: ControllerPlacement) -> bool {
    match spec.controller_key() {
        Some(_) => {
            placement == ControllerPlacement::Internal && spec.applies_to(params.controller.kind)
        }
        None => true,
    }
}

/// Every variable of the FMU for `params` and `placement`, in `modelDescription.xml` order.
pub fn variables(params: &Params, placement: ControllerPlacement) -> Vec<Variable> {
    let mut vars: Vec<Variable> = OUTPUTS
        .iter()
        .enumerate()
        .map(|(i, (name, unit, doc))| Variable {
            vr: VR_OUTPUTS + i as u32,
            name: name.to_string(),
            causality: Causality::Output,
            unit,
            description: doc.to_string(),
            start: None,
            range: None,
        })
        .collect();
    vars.push(Variable {
        vr: VR_XDD,
        name: "xdd".into(),
        causality: Causality::Input,
        unit: "m/s^2",
        description: "platform acceleration; between communication points extrapolated with \
                      the input derivatives given (order 1 to 3), else held"
            .into(),
        start: Some(0.0),
        range: Some(XDD_RANGE),
    });
    vars.push(Variable {
        vr: VR_X,
        name: "x".into(),
        causality: Causality::Input,
        unit: "m",
        description: "platform position (the model is written in the stroke u = y - x and is \
                      driven by xdd; x enters no equation)"
            .into(),
        start: Some(0.0),
        range: Some(X_RANGE),
    });
    if placement == ControllerPlacement::External {
        vars.push(Variable {
            vr: VR_V_IN_EXT,
            name: "v_in_ext".into(),
            causality: Causality::Input,
            unit: "V",
            description: "valve command from an external controller, sampled at the \
                          communication points; saturated to +-Vmax and read by the valve tau \
                          later, interpolated linearly between the samples"
                .into(),
            start: Some(0.0),
            range: Some(V_IN_EXT_RANGE),
        });
    }
    for (i, spec) in PARAMS.iter().enumerate() {
        if !exposes(spec, params, placement) {
            continue;
        }
        vars.push(Variable {
            vr: VR_PARAMS + i as u32,
            name: spec.key.to_string(),
            causality: Causality::Parameter {
                tunable: spec.controller_key().is_some(),
            },
            unit: spec.unit,
            // A unit FMI cannot declare (its base-unit exponents are integers; `m³/(s·√Pa)` has
            // a half) is named in the description instead.
            description: match fmi_unit(spec.unit) {
                None if spec.unit != "-" => {
                    format!("{} ({}, in {})", spec.doc, spec.symbol, spec.unit)
                }
                _ => format!("{} ({})", spec.doc, spec.symbol),
            },
            start: Some(spec.get(params)),
            range: Some((spec.min, spec.max)),
        });
    }
    vars
}

/// The FMI unit of a table unit: an ASCII name and the exponents of kg, m, s, A, rad.
fn fmi_unit(unit: &str) -> Option<(String, [i32; 5])> {
    // V = kg·m²/(A·s³); Pa = kg/(m·s²); N = kg·m/s²; Hz = 1/s.
    let exps: [i32; 5] = match unit {
        "-" | "" => return None,
        "kg" => [1, 0, 0, 0, 0],
        "m" => [0, 1, 0, 0, 0],
        "s" => [0, 0, 1, 0, 0],
        "V" => [1, 2, -3, -1, 0],
        "V/s" => [1, 2, -4, -1, 0],
        "Pa" => [1, -1, -2, 0, 0],
        "Hz" => [0, 0, -1, 0, 0],
        "1/Pa" => [-1, 1, 2, 0, 0],
        "m/s" => [0, 1, -1, 0, 0],
        "m/s^2" => [0, 1, -2, 0, 0],
        "m^3/s" => [0, 3, -1, 0, 0],
        "N" => [1, 1, -2, 0, 0],
        "N/m" => [1, 0, -2, 0, 0],
        "N·s/m" => [1, 0, -1, 0, 0],
        "m/V" => [-1, -1, 3, 1, 0],
        "V/m" => [1, 1, -3, -1, 0],
        "V·s/m" => [1, 1, -2, -1, 0],
        "m/(s·V)" => [-1, -1, 2, 1, 0],
        "rad/s" => [0, 0, -1, 0, 1],
        "kg/m³" => [1, -3, 0, 0, 0],
        "Pa·s" => [1, -1, -1, 0, 0],
        "m³/(s·Pa)" => [-1, 4, 1, 0, 0],
        "Pa/(m³/s)" => [1, -4, -1, 0, 0],
        "N·s²/m²" => [1, -1, 0, 0, 0],
        _ => return None,
    };
    // Modelica's unit syntax, which the importers read: `.` for a product, exponents as
    // digits.
    let name = unit
        .replace('·', ".")
        .replace('³', "3")
        .replace('²', "2")
        .replace('^', "");
    Some((name, exps))
}

/// XML text with `&`, `<`, `>`, `"` escaped.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number as XML attribute text that reads back to the same `f64`.
fn xml_number(v: f64) -> String {
    format!("{v:e}")
}

/// The FMU's GUID: a hash of what the shared library reads from the FMU (the preset text,
/// the placement) and of this crate's version, so that a library refuses a
/// `modelDescription.xml` or resources that are not its own.
pub fn guid(preset_toml: &str, placement: ControllerPlacement) -> String {
    // FNV-1a 64 twice (two offsets) for 128 bits.
    let fnv = |seed: u64| {
        let mut h = seed;
        for b in env!("CARGO_PKG_VERSION")
            .bytes()
            .chain([0])
            .chain(placement.name().bytes())
            .chain([0])
            .chain(preset_toml.bytes())
        {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01B3);
        }
        h
    };
    let (a, b) = (fnv(0xcbf2_9ce4_8422_2325), fnv(0x84222325_cbf29ce4));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// `modelDescription.xml` of the FMU for `preset` and `placement`.
pub fn model_description(preset: &Preset, placement: ControllerPlacement) -> String {
    let params = &preset.params;
    let vars = variables(params, placement);
    let toml = preset.to_toml();
    let mut units: Vec<(String, [i32; 5])> = Vec::new();
    for v in &vars {
        if let Some(u) = fmi_unit(v.unit)
            && !units.iter().any(|x| x.0 == u.0)
        {
            units.push(u);
        }
    }
    let mut x = String::new();
    let controller = match placement {
        ControllerPlacement::Internal => format!(
            "the preset's {} controller inside",
            params.controller.kind.name()
        ),
        ControllerPlacement::External => "the valve command as an input (v_in_ext)".to_string(),
    };
    let name = if preset.meta.name.is_empty() {
        "seat_twin".to_string()
    } else {
        preset.meta.name.clone()
    };
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="seat_twin ({})" guid="{}" description="{}" generationTool="seat-twin {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        xml_escape(&name),
        guid(&toml, placement),
        xml_escape(&format!(
            "Digital twin of a hydraulic active seat suspension (10-state nonlinear model), \
             preset {name}, {controller}; internal step {} s",
            crate::format::general(params.numerics.max_step_s)
        )),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true" maxOutputDerivativeOrder="0" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="false" canNotUseMemoryManagementFunctions="true"/>"#
    );
    let _ = writeln!(x, "  <UnitDefinitions>");
    for (name, e) in &units {
        let mut base = String::new();
        for (sym, v) in ["kg", "m", "s", "A", "rad"].iter().zip(e) {
            if *v != 0 {
                let _ = write!(base, r#" {sym}="{v}""#);
            }
        }
        let _ = writeln!(
            x,
            r#"    <Unit name="{}"><BaseUnit{base}/></Unit>"#,
            xml_escape(name)
        );
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="0" stepSize="{}"/>"#,
        xml_number(params.numerics.max_step_s)
    );
    let _ = writeln!(x, "  <ModelVariables>");
    for v in &vars {
        let (causality, variability, initial) = match v.causality {
            Causality::Input => ("input", "continuous", None),
            Causality::Output => ("output", "continuous", None),
            Causality::Parameter { tunable } => (
                "parameter",
                if tunable { "tunable" } else { "fixed" },
                Some("exact"),
            ),
        };
        let mut attrs = String::new();
        if let Some(u) = fmi_unit(v.unit) {
            let _ = write!(attrs, r#" unit="{}""#, xml_escape(&u.0));
        }
        if let Some((lo, hi)) = v.range {
            let _ = write!(
                attrs,
                r#" min="{}" max="{}""#,
                xml_number(lo),
                xml_number(hi)
            );
        }
        if let Some(s) = v.start {
            let _ = write!(attrs, r#" start="{}""#, xml_number(s));
        }
        let _ = writeln!(
            x,
            r#"    <ScalarVariable name="{}" valueReference="{}" description="{}" causality="{causality}" variability="{variability}"{}>"#,
            xml_escape(&v.name),
            v.vr,
            xml_escape(&v.description),
            initial.map_or(String::new(), |i| format!(r#" initial="{i}""#)),
        );
        let _ = writeln!(x, "      <Real{attrs}/>");
        let _ = writeln!(x, "    </ScalarVariable>");
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let outputs: Vec<usize> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    for section in ["Outputs", "InitialUnknowns"] {
        let _ = writeln!(x, "    <{section}>");
        for i in &outputs {
            let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
        }
        let _ = writeln!(x, "    </{section}>");
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

/// Why an FMU could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FmuExportError {
    /// The FMU's shared library is not where it was looked for.
    #[error(
        "the FMU's shared library {} is missing: it is built with the executable \
         (`cargo build --release` makes target/release/libseat_twin.so beside \
         target/release/seat-twin); build it, or give its path",
        .0.display()
    )]
    LibraryMissing(PathBuf),
    /// FMUs are made for Linux x86-64 only (binaries/linux64).
    #[error("FMU export supports Linux on x86-64 only (binaries/linux64); this is {0}")]
    Platform(String),
    /// Reading the library or writing the archive failed.
    #[error("{}: {error}", .file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// The archive could not be assembled.
    #[error(transparent)]
    Zip(#[from] super::zip::ZipError),
}

/// The shared library the FMU carries: `libseat_twin.so` beside the running executable
/// (`target/<profile>/` for a cargo build; one level up for a test binary in `deps/`).
pub fn library_beside_executable() -> PathBuf {
    let exe = std::env::current_exe().unwrap_or_default();
    let dir = exe.parent().map(Path::to_path_buf).unwrap_or_default();
    let name = format!("lib{MODEL_IDENTIFIER}.so");
    let here = dir.join(&name);
    if !here.exists()
        && dir.file_name().is_some_and(|n| n == "deps")
        && let Some(up) = dir.parent()
    {
        return up.join(&name);
    }
    here
}

/// What [`write`](fn@write) made.
#[derive(Debug, Clone, PartialEq)]
pub struct FmuSummary {
    /// Bytes of the archive.
    pub bytes: usize,
    /// Inputs, outputs and parameters.
    pub variables: usize,
    /// The GUID.
    pub guid: String,
}

/// Writes the FMU of `preset` with the controller `placement` to `out` atomically, carrying
/// the shared library `library` (see [`library_beside_executable`]). `progress(fraction,
/// stage)` is called as the work goes (for the app's background job).
pub fn write(
    preset: &Preset,
    placement: ControllerPlacement,
    library: &Path,
    out: &Path,
    progress: &mut dyn FnMut(f64, &str),
) -> Result<FmuSummary, FmuExportError> {
    if !(cfg!(target_os = "linux") && cfg!(target_arch = "x86_64")) {
        return Err(FmuExportError::Platform(format!(
            "{} on {}",
            std::env::consts::OS,
            std::env::consts::ARCH
        )));
    }
    progress(0.0, "reading the shared library");
    if !library.is_file() {
        return Err(FmuExportError::LibraryMissing(library.to_path_buf()));
    }
    let so = std::fs::read(library).map_err(|error| FmuExportError::Io {
        file: library.to_path_buf(),
        error,
    })?;
    progress(0.4, "writing modelDescription.xml");
    let description = model_description(preset, placement);
    let toml = preset.to_toml();
    let binary = format!("binaries/linux64/{MODEL_IDENTIFIER}.so");
    let files: [(&str, &[u8]); 4] = [
        ("modelDescription.xml", description.as_bytes()),
        (&binary, &so),
        ("resources/preset.toml", toml.as_bytes()),
        ("resources/controller", placement.name().as_bytes()),
    ];
    progress(0.6, "assembling the archive");
    let zip = super::zip::stored(&files)?;
    progress(0.8, "writing the archive");
    crate::fsutil::write_atomic_bytes(out, &zip).map_err(|error| FmuExportError::Io {
        file: out.to_path_buf(),
        error,
    })?;
    progress(1.0, "done");
    Ok(FmuSummary {
        bytes: zip.len(),
        variables: variables(&preset.params, placement).len(),
        guid: guid(&toml, placement),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_table_unit_has_an_fmi_unit() {
        for s in PARAMS.iter() {
            // Only a unit with a fractional exponent (√Pa) has no FMI form; it is named in
            // the variable's description.
            if s.unit != "-" && !s.unit.contains('√') {
                assert!(fmi_unit(s.unit).is_some(), "{}: {}", s.key, s.unit);
            }
        }
    }

    #[test]
    fn units_reduce_to_si_base_units() {
        // V·s/m = (kg·m²/(A·s³))·s/m = kg·m/(A·s²).
        assert_eq!(fmi_unit("V·s/m").unwrap().1, [1, 1, -2, -1, 0]);
        // m/(s·V) = m/s · A·s³/(kg·m²) = A·s²/(kg·m).
        assert_eq!(fmi_unit("m/(s·V)").unwrap().1, [-1, -1, 2, 1, 0]);
        assert_eq!(fmi_unit("m/s^2").unwrap().0, "m/s2");
        assert_eq!(fmi_unit("kg/m³").unwrap().0, "kg/m3");
    }

    #[test]
    fn external_controller_has_the_command_input_and_no_gains() {
        let p = Params::paper();
        let ext = variables(&p, ControllerPlacement::External);
        assert!(ext.iter().any(|v| v.name == "v_in_ext"));
        assert!(!ext.iter().any(|v| v.name.starts_with("controller.")));
        let int = variables(&p, ControllerPlacement::Internal);
        assert!(!int.iter().any(|v| v.name == "v_in_ext"));
        let kp = int
            .iter()
            .find(|v| v.name == "controller.kp_v_per_m")
            .unwrap();
        assert_eq!(kp.causality, Causality::Parameter { tunable: true });
        assert_eq!(kp.start, Some(-5.0));
        // Paper kind: no predictive or skyhook gains.
        assert!(!int.iter().any(|v| v.name == "controller.lead_s"));
    }

    #[test]
    fn guid_changes_with_the_preset_and_the_placement() {
        let a = guid("x", ControllerPlacement::Internal);
        assert_ne!(a, guid("y", ControllerPlacement::Internal));
        assert_ne!(a, guid("x", ControllerPlacement::External));
        assert_eq!(a.len(), 38);
    }
}
