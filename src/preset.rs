//! Preset files: the rig's parameters as TOML, versioned.
//!
//! A preset has an optional `[preset]` table (name, description, format version) and one table
//! per parameter group of [`Params`] (`[body]`, `[cylinder]`, `[valve]`, …), keys named with
//! their SI unit (`mass_kg`, `tau_s`, …). Unknown keys are an error (a typo must not be
//! ignored); missing keys take the paper's values. Files are written to a temporary name and
//! renamed, so a crash never leaves half a preset.

use crate::params::{
    BodyParams, ControllerParams, CylinderParams, EffectsParams, FluidParams, HoseParams,
    LinearParams, NumericsParams, ParamError, Params, PassiveParams, SupplyParams, ValveParams,
};
use serde::{Deserialize, Serialize};
use std::io::Write;
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
}

impl From<&Preset> for PresetFile {
    fn from(p: &Preset) -> Self {
        let q = &p.params;
        Self {
            preset: p.meta.clone(),
            body: q.body,
            cylinder: q.cylinder,
            hose: q.hose,
            supply: q.supply,
            valve: q.valve,
            fluid: q.fluid,
            controller: q.controller,
            passive: q.passive,
            linear: q.linear,
            numerics: q.numerics,
            effects: q.effects,
        }
    }
}

impl From<PresetFile> for Preset {
    fn from(f: PresetFile) -> Self {
        Self {
            meta: f.preset,
            params: Params {
                body: f.body,
                cylinder: f.cylinder,
                hose: f.hose,
                supply: f.supply,
                valve: f.valve,
                fluid: f.fluid,
                controller: f.controller,
                passive: f.passive,
                linear: f.linear,
                numerics: f.numerics,
                effects: f.effects,
            },
        }
    }
}

/// Why a preset could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// The file could not be read or written.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not valid TOML, an unknown key, or a value of the wrong type.
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
    #[error("{file}: {source}")]
    Invalid {
        /// The file.
        file: PathBuf,
        /// The range error.
        source: ParamError,
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

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, column)
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
        }
    }

    /// Parses preset text; `file` is used in messages only.
    pub fn from_toml(text: &str, file: &Path) -> Result<Self, PresetError> {
        let parsed: PresetFile = toml::from_str(text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or((1, 1));
            PresetError::Parse {
                file: file.to_path_buf(),
                line,
                column,
                message: e.message().trim().to_string(),
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
            .map_err(|source| PresetError::Invalid {
                file: file.to_path_buf(),
                source,
            })?;
        Ok(preset)
    }

    /// Reads and validates a preset file.
    pub fn load(path: &Path) -> Result<Self, PresetError> {
        let text = std::fs::read_to_string(path).map_err(|source| PresetError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::from_toml(&text, path)
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
        write_atomic(path, self.to_toml().as_bytes()).map_err(|source| PresetError::Io {
            file: path.to_path_buf(),
            source,
        })
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Loads a preset given as a path or as the name of a shipped preset (`paper`,
/// `paper-initial`, `consistent-delay`), looked up in `presets/` next to the working
/// directory or the executable.
pub fn resolve(name_or_path: &str) -> Result<Preset, PresetError> {
    let direct = Path::new(name_or_path);
    if direct.exists() {
        return Preset::load(direct);
    }
    for dir in preset_dirs() {
        let candidate = dir.join(format!("{name_or_path}.toml"));
        if candidate.exists() {
            return Preset::load(&candidate);
        }
    }
    if name_or_path == "paper" {
        return Ok(Preset::paper());
    }
    Err(PresetError::Io {
        file: direct.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no such preset file, and no shipped preset of that name in presets/",
        ),
    })
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
    fn round_trip() {
        let mut p = Preset::paper();
        p.params.valve.cd = 0.12;
        p.params.effects.friction.enabled = true;
        p.params.effects.friction.coulomb_n = 12.5;
        let back = Preset::from_toml(&p.to_toml(), Path::new("rt.toml")).unwrap();
        assert_eq!(back, p);
    }
}
