//! Preset files: the rig's parameters as TOML, versioned.
//!
//! A preset has an optional `[preset]` table (name, description, format version) and one table
//! per parameter group of [`Params`] (`[body]`, `[cylinder]`, `[valve]`, …), keys named with
//! their SI unit (`mass_kg`, `tau_s`, …). Unknown keys are an error (a typo must not be
//! ignored); missing keys take the paper's values. Files are written to a temporary name and
//! renamed, so a crash never leaves half a preset.

use crate::params::{
    BodyParams, ControllerParams, CorrectionParams, CylinderParams, EffectsParams, FluidParams,
    HoseParams, LinearParams, NumericsParams, ParamError, Params, PassiveParams, PlantParams,
    SensorParams, SupplyParams, ValveParams,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Current preset format version.
pub const FORMAT_VERSION: u32 = 1;

/// What a preset says about itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PresetMeta {
    /// Format version (1).
    pub format_version: u32,
    /// Short name.
    pub name: String,
    /// What this preset is for.
    pub description: String,
}

impl Default for PresetMeta {
    fn default() -> Self {
        Self {
            format_version: FORMAT_VERSION,
            name: String::new(),
            description: String::new(),
        }
    }
}

/// A preset: metadata and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// Metadata.
    pub meta: PresetMeta,
    /// Parameters (validated when loaded).
    pub params: Params,
    /// Values that a calibration found to change from record to record (empty otherwise).
    pub per_record: PerRecord,
}

/// Parameters a calibration found to drift from record to record (issue 20: oil warming up
/// through a campaign), each with its value per record, by the record's file name: the
/// `[per_record.cd]` table of a calibrated preset. `seat-twin replay` replays a listed record
/// with its own value and any other record with the preset's (`[valve]`'s `cd`, the campaign
/// value), and says which.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PerRecord {
    /// The valve's discharge coefficient per record file name [-], each in `valve.cd`'s
    /// range.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub cd: BTreeMap<String, f64>,
}

impl PerRecord {
    /// Whether nothing is listed.
    pub fn is_empty(&self) -> bool {
        self.cd.is_empty()
    }

    /// `params` with the values listed for the record file `file` (its name, without the
    /// folder), and whether any was listed for it.
    pub fn params_for(&self, params: &Params, file: &str) -> (Params, bool) {
        let mut p = *params;
        match self.cd.get(file) {
            Some(cd) => {
                p.plant.valve.cd = *cd;
                (p, true)
            }
            None => (p, false),
        }
    }

    /// Checks every value against its parameter's range, naming it `per_record.cd."file"`.
    pub fn validate(&self) -> Result<(), ParamError> {
        let (min, max) =
            crate::params::spec("valve.cd").map_or((f64::MIN, f64::MAX), |s| (s.min, s.max));
        for (file, cd) in &self.cd {
            crate::params::check(&format!("per_record.cd.\"{file}\""), *cd, min, max, "-")?;
        }
        Ok(())
    }
}

/// The file layout (one table per parameter group).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct PresetFile {
    preset: PresetMeta,
    body: BodyParams,
    cylinder: CylinderParams,
    hose: HoseParams,
    supply: SupplyParams,
    valve: ValveParams,
    fluid: FluidParams,
    controller: ControllerParams,
    passive: PassiveParams,
    linear: LinearParams,
    numerics: NumericsParams,
    effects: EffectsParams,
    /// The records' sensors (exact unless a calibration found a property).
    sensors: SensorParams,
    /// Terms beyond the effect library a calibration proposed (zero unless it did).
    corrections: CorrectionParams,
    /// Values per record, when a calibration found a drift (absent otherwise).
    #[serde(skip_serializing_if = "PerRecord::is_empty")]
    per_record: PerRecord,
}

impl From<&Preset> for PresetFile {
    fn from(p: &Preset) -> Self {
        let q = &p.params;
        Self {
            preset: p.meta.clone(),
            body: q.plant.body,
            cylinder: q.plant.cylinder,
            hose: q.plant.hose,
            supply: q.plant.supply,
            valve: q.plant.valve,
            fluid: q.plant.fluid,
            controller: q.controller,
            passive: q.passive,
            linear: q.linear,
            numerics: q.numerics,
            effects: q.plant.effects,
            sensors: q.sensors,
            corrections: q.plant.corrections,
            per_record: p.per_record.clone(),
        }
    }
}

impl From<PresetFile> for Preset {
    fn from(f: PresetFile) -> Self {
        Self {
            meta: f.preset,
            params: Params {
                plant: PlantParams {
                    body: f.body,
                    cylinder: f.cylinder,
                    hose: f.hose,
                    supply: f.supply,
                    valve: f.valve,
                    fluid: f.fluid,
                    effects: f.effects,
                    corrections: f.corrections,
                },
                controller: f.controller,
                passive: f.passive,
                linear: f.linear,
                numerics: f.numerics,
                sensors: f.sensors,
            },
            per_record: f.per_record,
        }
    }
}

/// Largest preset file [`Preset::load`] reads: 1 MiB (the shipped presets are a few KiB).
pub const MAX_PRESET_BYTES: u64 = 1024 * 1024;

/// Why a preset could not be read or written. Every message starts with the file and says
/// everything once: the errors carry their cause in the message, not as a separate
/// [`source`](std::error::Error::source).
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// The file could not be read or written.
    #[error("{file}: {error}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The file is larger than [`MAX_PRESET_BYTES`] (or is a device that never ends); refused
    /// before it is read whole.
    #[error("{file}: {what} the limit of {limit} bytes (1 MiB) for a preset; is it a preset file?")]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// "N bytes is over" or "reads past", depending on whether the size is known.
        what: String,
        /// The limit \[bytes\].
        limit: u64,
    },
    /// Not UTF-8 text, not valid TOML, an unknown key, or a value of the wrong type (then the
    /// message names the key, e.g. `` `body.mass_kg`: invalid type: map, expected f64 ``).
    #[error("{file}: line {line}, column {column}: {message}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A value outside its range.
    #[error("{file}: {}{error}", located(*.at))]
    Invalid {
        /// The file.
        file: PathBuf,
        /// 1-based line and column of the value, where the file sets it (a default that
        /// another value puts out of range has none).
        at: Option<(usize, usize)>,
        /// The range error.
        error: ParamError,
    },
    /// A newer or unknown format version.
    #[error(
        "{file}: preset format_version {found} is not supported (this build reads {FORMAT_VERSION})"
    )]
    Version {
        /// The file.
        file: PathBuf,
        /// Version in the file.
        found: u32,
    },
}

/// "line L, column C: " for a located error, "" for one without a place.
fn located(at: Option<(usize, usize)>) -> String {
    at.map(|(line, column)| format!("line {line}, column {column}: "))
        .unwrap_or_default()
}

/// The segments of a dotted parameter name: `per_record.cd."a.csv"` → per_record, cd, a.csv.
fn segments(name: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    for c in name.chars() {
        match c {
            '"' => quoted = !quoted,
            '.' if !quoted => out.push(String::new()),
            c => out.last_mut().expect("one segment at least").push(c),
        }
    }
    out
}

/// The byte offset in `text` of the value of the dotted parameter `name`, where the file sets
/// it.
fn value_offset(text: &str, name: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    fn find<'t, 'i>(table: &'t DeTable<'i>, path: &[String]) -> Option<usize> {
        let (first, rest) = path.split_first()?;
        let (_, v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == first)?;
        match (rest.is_empty(), v.get_ref()) {
            (true, _) => Some(v.span().start),
            (false, DeValue::Table(t)) => find(t, rest),
            (false, _) => None,
        }
    }
    let doc = DeTable::parse(text).ok()?;
    find(doc.get_ref(), &segments(name))
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    crate::fsutil::line_column(text.as_bytes(), offset)
}

/// The dotted key (`body.mass_kg`) whose value spans `offset` in `text`, if any: the deepest
/// one, so that an error at a value names its key.
fn key_at(text: &str, offset: usize) -> Option<String> {
    use toml::de::{DeTable, DeValue};
    let contains = |span: std::ops::Range<usize>| {
        span.start <= offset && offset < span.end.max(span.start + 1)
    };
    // A table's own span may be just its header, so its entries are searched first.
    fn walk(
        table: &DeTable<'_>,
        contains: &dyn Fn(std::ops::Range<usize>) -> bool,
    ) -> Option<Vec<String>> {
        for (k, v) in table.iter() {
            let key = k.get_ref().to_string();
            match v.get_ref() {
                DeValue::Table(t) => {
                    if let Some(mut p) = walk(t, contains) {
                        p.insert(0, key);
                        return Some(p);
                    }
                }
                DeValue::Array(a) => {
                    for (i, item) in a.iter().enumerate() {
                        let inner = match item.get_ref() {
                            DeValue::Table(t) => walk(t, contains),
                            _ => None,
                        };
                        if let Some(mut p) = inner {
                            p.insert(0, format!("{key}[{i}]"));
                            return Some(p);
                        }
                        if contains(item.span()) {
                            return Some(vec![format!("{key}[{i}]")]);
                        }
                    }
                }
                _ => {}
            }
            if contains(v.span()) {
                return Some(vec![key]);
            }
        }
        None
    }
    let doc = DeTable::parse(text).ok()?;
    walk(doc.get_ref(), &contains).map(|p| p.join("."))
}

impl Preset {
    /// The paper's adjusted twin.
    pub fn paper() -> Self {
        Self {
            meta: PresetMeta {
                name: "paper".into(),
                description: "The paper's adjusted digital twin (Cd = 0.1506, τ = 17.5 ms)".into(),
                ..Default::default()
            },
            params: Params::paper(),
            per_record: PerRecord::default(),
        }
    }

    /// Parses preset text; `file` is used in messages only.
    pub fn from_toml(text: &str, file: &Path) -> Result<Self, PresetError> {
        let parsed: PresetFile = toml::from_str(text).map_err(|e| {
            let start = e.span().map(|s| s.start);
            let (line, column) = start.map(|s| line_column(text, s)).unwrap_or((1, 1));
            let message = e.message().trim().to_string();
            // Type and range errors of serde point at a value without naming its key.
            let message = match start.and_then(|s| key_at(text, s)) {
                Some(key) if !message.contains(&format!("`{key}`")) => {
                    format!("`{key}`: {message}")
                }
                _ => message,
            };
            PresetError::Parse {
                file: file.to_path_buf(),
                line,
                column,
                message,
            }
        })?;
        if parsed.preset.format_version != FORMAT_VERSION {
            return Err(PresetError::Version {
                file: file.to_path_buf(),
                found: parsed.preset.format_version,
            });
        }
        let preset = Preset::from(parsed);
        preset
            .params
            .validate()
            .and_then(|()| preset.per_record.validate())
            .map_err(|error| {
                let at = match &error {
                    ParamError::OutOfRange { name, .. } => value_offset(text, name),
                    // It names its key first, between backticks.
                    ParamError::Inconsistent(msg) => msg
                        .split('`')
                        .nth(1)
                        .and_then(|name| value_offset(text, name)),
                };
                PresetError::Invalid {
                    file: file.to_path_buf(),
                    at: at.map(|o| line_column(text, o)),
                    error,
                }
            })?;
        Ok(preset)
    }

    /// Parses a preset from the raw bytes of a file, which must be UTF-8 text of at most
    /// [`MAX_PRESET_BYTES`]; `file` is used in messages only.
    pub fn from_bytes(bytes: &[u8], file: &Path) -> Result<Self, PresetError> {
        if bytes.len() as u64 > MAX_PRESET_BYTES {
            return Err(PresetError::TooLarge {
                file: file.to_path_buf(),
                what: format!("{} bytes is over", bytes.len()),
                limit: MAX_PRESET_BYTES,
            });
        }
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let at = e.valid_up_to();
            let (line, column) = crate::fsutil::line_column(bytes, at);
            PresetError::Parse {
                file: file.to_path_buf(),
                line,
                column,
                message: format!(
                    "not UTF-8 text: invalid byte 0x{:02x}; a preset is a TOML text file",
                    bytes[at]
                ),
            }
        })?;
        if let Some(at) = text.find('\0') {
            let (line, column) = line_column(text, at);
            return Err(PresetError::Parse {
                file: file.to_path_buf(),
                line,
                column,
                message: "a NUL byte: a preset is a TOML text file".into(),
            });
        }
        Self::from_toml(text, file)
    }

    /// Reads and validates a preset file. Files over [`MAX_PRESET_BYTES`] are refused before
    /// they are read whole (a device such as `/dev/zero` after reading just past the limit).
    pub fn load(path: &Path) -> Result<Self, PresetError> {
        use std::io::Read;
        let io = |error| PresetError::Io {
            file: path.to_path_buf(),
            error,
        };
        let file = crate::fsutil::open_input(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if meta.is_dir() {
            return Err(io(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a directory, not a preset file",
            )));
        }
        if meta.is_file() && meta.len() > MAX_PRESET_BYTES {
            return Err(PresetError::TooLarge {
                file: path.to_path_buf(),
                what: format!("{} bytes is over", meta.len()),
                limit: MAX_PRESET_BYTES,
            });
        }
        let mut bytes = Vec::new();
        file.take(MAX_PRESET_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() as u64 > MAX_PRESET_BYTES {
            return Err(PresetError::TooLarge {
                file: path.to_path_buf(),
                what: "reads past".into(),
                limit: MAX_PRESET_BYTES,
            });
        }
        Self::from_bytes(&bytes, path)
    }

    /// The preset as TOML text.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string_pretty(&PresetFile::from(self))
            .unwrap_or_else(|e| format!("# could not serialise preset: {e}\n"));
        format!(
            "# seat-twin preset. SI units; each key names its unit. Missing keys take the\n\
             # paper's values; unknown keys are an error.\n\n{body}"
        )
    }

    /// Writes the preset atomically (temporary file in the same directory, then rename).
    pub fn save(&self, path: &Path) -> Result<(), PresetError> {
        write_atomic(path, self.to_toml().as_bytes()).map_err(|error| PresetError::Io {
            file: path.to_path_buf(),
            error,
        })
    }
}

/// Writes `bytes` to `path` atomically: [`crate::fsutil::write_atomic_bytes`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    crate::fsutil::write_atomic_bytes(path, bytes)
}

/// Loads a preset given as a path or as the name of a shipped preset (`paper`,
/// `paper-initial`, `consistent-delay`), looked up in `presets/` next to the working
/// directory or the executable ([`locate`]).
pub fn resolve(name_or_path: &str) -> Result<Preset, PresetError> {
    match locate(name_or_path) {
        Some(path) => Preset::load(&path),
        None if name_or_path == "paper" => Ok(Preset::paper()),
        None => Err(PresetError::Io {
            file: PathBuf::from(name_or_path),
            error: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no such preset file, and no shipped preset of that name in presets/",
            ),
        }),
    }
}

/// The file [`resolve`] reads for `name_or_path`: the path itself when something is there
/// (a dangling link or a link loop included, so that its own error is told rather than "no
/// such file"), else `presets/NAME.toml` in the first of [`preset_dirs`] that has it; `None`
/// when neither exists (the built-in `paper` preset needs no file).
pub fn locate(name_or_path: &str) -> Option<PathBuf> {
    let direct = Path::new(name_or_path);
    if std::fs::symlink_metadata(direct).is_ok() {
        return Some(direct.to_path_buf());
    }
    preset_dirs()
        .into_iter()
        .map(|dir| dir.join(format!("{name_or_path}.toml")))
        .find(|candidate| candidate.exists())
}

/// Directories searched for shipped presets: `./presets`, the crate's `presets/` (when run
/// from a checkout) and `presets/` beside the executable.
pub fn preset_dirs() -> Vec<PathBuf> {
    let mut dirs = vec![PathBuf::from("presets")];
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("presets"));
    if let Ok(exe) = std::env::current_exe()
        && let Some(parent) = exe.parent()
    {
        dirs.push(parent.join("presets"));
    }
    dirs
}

/// The shipped presets found on disk: `(name, path)`.
pub fn shipped_presets() -> Vec<(String, PathBuf)> {
    let mut out: Vec<(String, PathBuf)> = Vec::new();
    for dir in preset_dirs() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut found: Vec<_> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        found.sort();
        for p in found {
            if let Some(stem) = p.file_stem().and_then(|s| s.to_str())
                && !out.iter().any(|(n, _)| n == stem)
            {
                out.push((stem.to_string(), p));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{ControllerKind, PARAMS};

    /// The key of every entry names the field it reads, as the preset file spells it: the
    /// paper's parameters serialised to TOML hold, at each dotted key, the value `get` reads
    /// (for each controller kind, since a preset writes only its kind's gains).
    #[test]
    fn keys_match_the_preset_file() {
        for kind in ControllerKind::ALL {
            let mut p = Params::paper();
            p.controller.kind = kind;
            let preset = Preset {
                meta: Default::default(),
                params: p,
                per_record: Default::default(),
            };
            let doc: toml::Value = toml::from_str(&preset.to_toml()).unwrap();
            for s in PARAMS.iter().filter(|s| s.applies_to(p.controller.kind)) {
                let mut v = &doc;
                for part in s.key.split('.') {
                    v = v
                        .get(part)
                        .unwrap_or_else(|| panic!("{} not in the preset", s.key));
                }
                let in_file = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
                assert_eq!(in_file, Some(s.get(&p)), "{}", s.key);
            }
        }
    }

    #[test]
    fn empty_file_is_the_paper() {
        let p = Preset::from_toml("", Path::new("x.toml")).unwrap();
        assert_eq!(p.params, Params::paper());
    }

    #[test]
    fn unknown_key_is_an_error_with_line() {
        let text = "[valve]\ncd = 0.15\ntua_s = 0.01\n";
        let e = Preset::from_toml(text, Path::new("typo.toml")).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("typo.toml: line 3"), "{msg}");
        assert!(msg.contains("tua_s"), "{msg}");
    }

    #[test]
    fn out_of_range_names_the_parameter() {
        let e = Preset::from_toml("[body]\nmass_kg = 0\n", Path::new("m.toml")).unwrap_err();
        assert!(e.to_string().contains("body.mass_kg"), "{e}");
    }

    #[test]
    fn out_of_range_names_its_line_and_column() {
        let cases = [
            (
                "[preset]\nname = \"x\"\n\n[valve]\ncd = -1\n",
                "v.toml: line 5, column 6: parameter `valve.cd` = -1 is outside the allowed \
                 range [0.001, 1] (dimensionless)",
            ),
            (
                "[effects.friction]\nenabled = true\ncoulomb_n   = -5\n",
                "v.toml: line 3, column 15: parameter `effects.friction.coulomb_n` = -5 is \
                 outside the allowed range [0, 5000] N",
            ),
            (
                "[effects]\nfriction = { enabled = true, coulomb_n = 1e9 }\n",
                "v.toml: line 2, column 42: parameter `effects.friction.coulomb_n`",
            ),
            (
                "[per_record.cd]\n\"a.b.csv\" = 7\n",
                "v.toml: line 2, column 13: parameter `per_record.cd.\"a.b.csv\"` = 7",
            ),
        ];
        for (text, expected) in cases {
            let e = Preset::from_toml(text, Path::new("v.toml")).unwrap_err();
            assert!(e.to_string().starts_with(expected), "{e}");
        }
    }

    #[test]
    fn round_trip() {
        let mut p = Preset::paper();
        p.params.plant.valve.cd = 0.12;
        p.params.plant.effects.friction.enabled = true;
        p.params.plant.effects.friction.coulomb_n = 12.5;
        let back = Preset::from_toml(&p.to_toml(), Path::new("rt.toml")).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn type_errors_name_the_key() {
        for (text, expected) in [
            (
                "[body]\nmass_kg = { a = 1 }\n",
                "k.toml: line 2, column 11: `body.mass_kg`: invalid type: map, expected f64",
            ),
            (
                "body.mass_kg = true\n",
                "k.toml: line 1, column 16: `body.mass_kg`: invalid type: boolean `true`, \
                 expected f64",
            ),
            (
                "[effects]\nfriction = { coulomb_n = \"x\" }\n",
                "k.toml: line 2, column 26: `effects.friction.coulomb_n`: invalid type: \
                 string \"x\", expected f64",
            ),
        ] {
            let e = Preset::from_toml(text, Path::new("k.toml")).unwrap_err();
            assert_eq!(e.to_string(), expected);
        }
    }

    #[test]
    fn oversized_binary_and_directory_presets_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.toml");
        std::fs::File::create(&big)
            .unwrap()
            .set_len(MAX_PRESET_BYTES + 1)
            .unwrap();
        let e = Preset::load(&big).unwrap_err();
        assert!(matches!(e, PresetError::TooLarge { .. }), "{e}");
        assert!(
            e.to_string()
                .ends_with("big.toml: 1048577 bytes is over the limit of 1048576 bytes (1 MiB) for a preset; is it a preset file?"),
            "{e}"
        );
        let e = Preset::load(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/dev/zero: reads past the limit of 1048576 bytes (1 MiB) for a preset; is it a \
             preset file?"
        );
        let e = Preset::load(dir.path()).unwrap_err();
        assert!(
            e.to_string()
                .ends_with(": is a directory, not a preset file"),
            "{e}"
        );
        let e = Preset::from_bytes(b"[body]\nmass_kg = \xff\n", Path::new("b.toml")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "b.toml: line 2, column 11: not UTF-8 text: invalid byte 0xff; a preset is a TOML \
             text file"
        );
    }

    #[test]
    fn saved_presets_honour_the_umask() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("p.toml");
        Preset::paper().save(&f).unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // 0666 less the umask (Linux reports it in /proc), not a private temporary 0600.
            let umask = std::fs::read_to_string("/proc/self/status")
                .ok()
                .and_then(|s| {
                    s.lines()
                        .find_map(|l| l.strip_prefix("Umask:"))
                        .and_then(|v| u32::from_str_radix(v.trim(), 8).ok())
                });
            if let Some(umask) = umask {
                let mode = f.metadata().unwrap().permissions().mode() & 0o777;
                assert_eq!(mode, 0o666 & !umask, "mode {mode:o}, umask {umask:o}");
            }
        }
        assert_eq!(Preset::load(&f).unwrap(), Preset::paper());
    }
}
