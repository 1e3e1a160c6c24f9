//! The FMI 2.0 co-simulation C API of the FMU, exported from this crate's `cdylib`
//! (`libseat_twin.so`, shipped in the FMU as `binaries/linux64/seat_twin.so`).
//!
//! Written here rather than with an FMI crate: the crates that export an FMU (`fmi-export`)
//! target FMI 3.0 only and generate their bindings with bindgen, which needs libclang at
//! build time. FMI 2.0's co-simulation API is 34 plain C functions over doubles.
//!
//! Every function checks its pointers, runs its work inside `catch_unwind`, and answers a bad
//! call (an unknown value reference, a value out of range, a call in the wrong state) with
//! `fmi2Error` and a message through the importer's logger: the host never crashes. The
//! model-exchange-only and non-Real functions answer `fmi2Error` with a message.

pub mod slave;

use super::fmu::{ControllerPlacement, MODEL_IDENTIFIER};
use slave::Slave;
use std::ffi::{CStr, CString, c_char, c_int, c_uint, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

type Status = c_int;
const OK: Status = 0;
const ERROR: Status = 3;
const FATAL: Status = 4;

/// `fmi2CallbackLogger`: variadic, called here with the format `"%s"` and one string.
type Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    logger: Option<Logger>,
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    component_environment: *mut c_void,
}

/// One instance (an `fmi2Component`).
struct Instance {
    name: CString,
    logger: Option<Logger>,
    environment: *mut c_void,
    logging_on: bool,
    placement: ControllerPlacement,
    preset: crate::params::Params,
    slave: Slave,
    /// The `fmi2FMUstate`s this instance handed out and has not freed.
    states: Vec<*mut Slave>,
}

impl Instance {
    fn log(&self, status: Status, category: &str, message: &str) {
        if status == OK && !self.logging_on {
            return;
        }
        let Some(logger) = self.logger else { return };
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the logger is the importer's, called with its documented arguments; the
        // format "%s" consumes the one string passed.
        unsafe {
            logger(
                self.environment,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            );
        }
    }

    /// `fmi2OK` for `Ok`, else logs the message and answers `fmi2Error`.
    fn status(&mut self, what: &str, r: Result<(), String>) -> Status {
        match r {
            Ok(()) => OK,
            Err(e) => {
                self.log(ERROR, "logStatusError", &format!("{what}: {e}"));
                ERROR
            }
        }
    }
}

/// Runs `f` on the instance behind `c`, catching a panic (then `fmi2Fatal`).
fn with_instance(c: *mut c_void, f: impl FnOnce(&mut Instance) -> Status) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null component is one `fmi2Instantiate` returned (the FMI contract).
    let inst = unsafe { &mut *(c as *mut Instance) };
    match catch_unwind(AssertUnwindSafe(|| f(inst))) {
        Ok(s) => s,
        Err(_) => {
            inst.slave.fail();
            inst.log(
                FATAL,
                "logStatusFatal",
                "internal error (a panic was caught)",
            );
            FATAL
        }
    }
}

/// The `n` elements at `p` (an empty slice for `n = 0`), `None` for a null pointer with
/// `n > 0`.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: the importer passes arrays of `n` elements (the FMI contract).
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as for `slice`.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// The directory a `file:` URI names (`file:///a/b`, `file:/a/b`, `file://localhost/a/b`),
/// percent-decoded (`None` for another scheme or a path that is not UTF-8).
fn uri_to_path(uri: &str) -> Option<std::path::PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let rest = if let Some(r) = rest.strip_prefix("//") {
        if r.starts_with('/') {
            r
        } else {
            r.strip_prefix("localhost")?
        }
    } else {
        rest
    };
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok().map(std::path::PathBuf::from)
}

/// The preset and placement in the FMU's resources, checked against the GUID.
fn read_resources(
    resource_uri: &str,
    guid: &str,
) -> Result<(crate::params::Params, ControllerPlacement), String> {
    let dir = uri_to_path(resource_uri)
        .ok_or_else(|| format!("fmuResourceLocation {resource_uri:?} is not a file: URI"))?;
    let preset_path = dir.join("preset.toml");
    let text = std::fs::read_to_string(&preset_path)
        .map_err(|e| format!("{}: {e}", preset_path.display()))?;
    let placement_path = dir.join("controller");
    let placement_text = std::fs::read_to_string(&placement_path)
        .map_err(|e| format!("{}: {e}", placement_path.display()))?;
    let placement = ControllerPlacement::from_name(&placement_text).ok_or_else(|| {
        format!(
            "{}: {placement_text:?} is neither internal nor external",
            placement_path.display()
        )
    })?;
    let preset =
        crate::preset::Preset::from_toml(&text, &preset_path).map_err(|e| e.to_string())?;
    let expected = super::fmu::guid(&preset.to_toml(), placement);
    if guid != expected {
        return Err(format!(
            "fmuGUID {guid} is not this FMU's ({expected}): the modelDescription.xml and the \
             resources come from different exports"
        ));
    }
    Ok((preset.params, placement))
}

/// `fmi2GetTypesPlatform`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate`: a co-simulation instance, or null (with a logged reason).
///
/// # Safety
/// The FMI contract: valid C strings or null, a valid callback struct or null.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    fmu_guid: *const c_char,
    fmu_resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> *mut c_void {
    let result = catch_unwind(|| {
        // SAFETY: the importer's callback struct, checked for null.
        let (logger, environment) = match unsafe { functions.as_ref() } {
            Some(f) => (f.logger, f.component_environment),
            None => (None, std::ptr::null_mut()),
        };
        let cstr = |p: *const c_char| {
            // SAFETY: a C string from the importer, checked for null.
            (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
        };
        let name = cstr(instance_name).unwrap_or_else(|| MODEL_IDENTIFIER.to_string());
        let mut inst = Instance {
            name: CString::new(name.replace('\0', " ")).unwrap_or_default(),
            logger,
            environment,
            logging_on: logging_on != 0,
            placement: ControllerPlacement::Internal,
            preset: crate::params::Params::paper(),
            slave: Slave::new(
                crate::params::Params::paper(),
                ControllerPlacement::Internal,
            ),
            states: Vec::new(),
        };
        let checked = (|| {
            if fmu_type != 1 {
                return Err(
                    "this FMU supports co-simulation only (fmuType fmi2CoSimulation)".to_string(),
                );
            }
            let guid = cstr(fmu_guid).ok_or("fmuGUID is null")?;
            let uri = cstr(fmu_resource_location).ok_or("fmuResourceLocation is null")?;
            read_resources(&uri, &guid).map(|(params, placement)| (params, placement, guid))
        })();
        match checked {
            Ok((params, placement, guid)) => {
                inst.placement = placement;
                inst.preset = params;
                inst.slave = Slave::new(params, placement).with_guid(&guid);
                Box::into_raw(Box::new(inst)) as *mut c_void
            }
            Err(e) => {
                inst.log(ERROR, "logStatusError", &format!("fmi2Instantiate: {e}"));
                std::ptr::null_mut()
            }
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi2FreeInstance`.
///
/// # Safety
/// `c` is null or an instance from `fmi2Instantiate`, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: *mut c_void) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(|| {
        // SAFETY: an instance from fmi2Instantiate, freed once (the FMI contract).
        let inst = unsafe { Box::from_raw(c as *mut Instance) };
        for s in &inst.states {
            // SAFETY: states this instance handed out and has not freed.
            drop(unsafe { Box::from_raw(*s) });
        }
    });
}

/// `fmi2SetDebugLogging`: `loggingOn` switches the OK-level messages; categories are ignored.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    logging_on: c_int,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    with_instance(c, |inst| {
        inst.logging_on = logging_on != 0;
        OK
    })
}

/// `fmi2SetupExperiment`: the start time (tolerance and stop time do not change the fixed-step
/// twin).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: c_int,
    _stop_time: f64,
) -> Status {
    with_instance(c, |inst| {
        let r = inst.slave.setup(start_time);
        inst.status("fmi2SetupExperiment", r)
    })
}

/// `fmi2EnterInitializationMode`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> Status {
    with_instance(c, |inst| {
        let r = inst.slave.enter_initialization();
        inst.status("fmi2EnterInitializationMode", r)
    })
}

/// `fmi2ExitInitializationMode`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> Status {
    with_instance(c, |inst| {
        let r = inst.slave.exit_initialization();
        inst.status("fmi2ExitInitializationMode", r)
    })
}

/// `fmi2Terminate`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: *mut c_void) -> Status {
    with_instance(c, |inst| {
        let r = inst.slave.terminate();
        inst.status("fmi2Terminate", r)
    })
}

/// `fmi2Reset`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: *mut c_void) -> Status {
    with_instance(c, |inst| {
        inst.slave.reset();
        OK
    })
}

/// `fmi2GetReal`.
///
/// # Safety
/// `vr` and `value` point to `n` elements (or are null with `n = 0`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    value: *mut f64,
) -> Status {
    with_instance(c, |inst| {
        // SAFETY: arrays of n elements (checked for null).
        let (Some(vrs), Some(out)) = (unsafe { slice(vr, n) }, unsafe { slice_mut(value, n) })
        else {
            return inst.status("fmi2GetReal", Err("a null array".into()));
        };
        for (v, o) in vrs.iter().zip(out.iter_mut()) {
            match inst.slave.get(*v) {
                Ok(x) => *o = x,
                Err(e) => return inst.status("fmi2GetReal", Err(e)),
            }
        }
        OK
    })
}

/// `fmi2SetReal`: inputs and parameters, each checked against its range.
///
/// # Safety
/// `vr` and `value` point to `n` elements (or are null with `n = 0`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    value: *const f64,
) -> Status {
    with_instance(c, |inst| {
        // SAFETY: arrays of n elements (checked for null).
        let (Some(vrs), Some(vals)) = (unsafe { slice(vr, n) }, unsafe { slice(value, n) }) else {
            return inst.status("fmi2SetReal", Err("a null array".into()));
        };
        for (v, x) in vrs.iter().zip(vals) {
            let r = inst.slave.set(*v, *x);
            if r.is_err() {
                return inst.status("fmi2SetReal", r);
            }
        }
        OK
    })
}

/// `fmi2SetRealInputDerivatives`: derivatives of order 1–3 of `xdd` (and of `x`, unused).
///
/// # Safety
/// `vr`, `order` and `value` point to `n` elements (or are null with `n = 0`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    order: *const c_int,
    value: *const f64,
) -> Status {
    with_instance(c, |inst| {
        // SAFETY: arrays of n elements (checked for null).
        let arrays = unsafe { (slice(vr, n), slice(order, n), slice(value, n)) };
        let (Some(vrs), Some(orders), Some(vals)) = arrays else {
            return inst.status("fmi2SetRealInputDerivatives", Err("a null array".into()));
        };
        for ((v, o), x) in vrs.iter().zip(orders).zip(vals) {
            let r = inst.slave.set_derivative(*v, *o, *x);
            if r.is_err() {
                return inst.status("fmi2SetRealInputDerivatives", r);
            }
        }
        OK
    })
}

/// `fmi2DoStep`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: *mut c_void,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior: c_int,
) -> Status {
    with_instance(c, |inst| {
        let r = inst
            .slave
            .do_step(current_communication_point, communication_step_size);
        inst.status("fmi2DoStep", r)
    })
}

/// `fmi2CancelStep`: steps are synchronous, there is nothing to cancel.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2CancelStep(c: *mut c_void) -> Status {
    with_instance(c, |inst| {
        inst.status(
            "fmi2CancelStep",
            Err("steps run synchronously; there is no step to cancel".into()),
        )
    })
}

/// `fmi2GetFMUstate`: a copy of the instance's state (a new one, or into `*state`).
///
/// # Safety
/// `state` points to an `fmi2FMUstate` (null or one this instance handed out).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    with_instance(c, |inst| {
        if state.is_null() {
            return inst.status("fmi2GetFMUstate", Err("FMUstate is a null pointer".into()));
        }
        // SAFETY: checked for null above.
        let slot = unsafe { &mut *state };
        let existing = *slot as *mut Slave;
        if !existing.is_null() && inst.states.contains(&existing) {
            // SAFETY: a state this instance handed out and has not freed.
            unsafe { *existing = inst.slave.clone() };
        } else {
            let p = Box::into_raw(Box::new(inst.slave.clone()));
            inst.states.push(p);
            *slot = p as *mut c_void;
        }
        OK
    })
}

/// `fmi2SetFMUstate`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetFMUstate(c: *mut c_void, state: *mut c_void) -> Status {
    with_instance(c, |inst| {
        let p = state as *mut Slave;
        if !inst.states.contains(&p) {
            return inst.status(
                "fmi2SetFMUstate",
                Err("the FMUstate is not one this instance handed out (or it was freed)".into()),
            );
        }
        // SAFETY: a live state of this instance.
        inst.slave = unsafe { (*p).clone() };
        OK
    })
}

/// `fmi2FreeFMUstate`.
///
/// # Safety
/// `state` points to an `fmi2FMUstate`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    with_instance(c, |inst| {
        if state.is_null() {
            return OK;
        }
        // SAFETY: checked for null.
        let slot = unsafe { &mut *state };
        let p = *slot as *mut Slave;
        if p.is_null() {
            return OK;
        }
        let Some(i) = inst.states.iter().position(|s| *s == p) else {
            return inst.status(
                "fmi2FreeFMUstate",
                Err("the FMUstate is not one this instance handed out".into()),
            );
        };
        inst.states.swap_remove(i);
        // SAFETY: handed out by this instance and now forgotten by it.
        drop(unsafe { Box::from_raw(p) });
        *slot = std::ptr::null_mut();
        OK
    })
}

fn state_ref(inst: &Instance, state: *mut c_void) -> Option<&Slave> {
    let p = state as *mut Slave;
    // SAFETY: a live state of this instance.
    inst.states.contains(&p).then(|| unsafe { &*p })
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// `size` points to a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: *mut c_void,
    state: *mut c_void,
    size: *mut usize,
) -> Status {
    with_instance(c, |inst| {
        let Some(s) = state_ref(inst, state) else {
            return inst.status("fmi2SerializedFMUstateSize", Err("unknown FMUstate".into()));
        };
        if size.is_null() {
            return inst.status("fmi2SerializedFMUstateSize", Err("size is null".into()));
        }
        let n = s.serialize().len();
        // SAFETY: checked for null.
        unsafe { *size = n };
        OK
    })
}

/// `fmi2SerializeFMUstate`.
///
/// # Safety
/// `bytes` points to `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: *mut c_void,
    state: *mut c_void,
    bytes: *mut c_char,
    size: usize,
) -> Status {
    with_instance(c, |inst| {
        let Some(s) = state_ref(inst, state) else {
            return inst.status("fmi2SerializeFMUstate", Err("unknown FMUstate".into()));
        };
        let data = s.serialize();
        if data.len() != size || bytes.is_null() {
            return inst.status(
                "fmi2SerializeFMUstate",
                Err(format!(
                    "the buffer holds {size} bytes; the state needs {}",
                    data.len()
                )),
            );
        }
        // SAFETY: `size` bytes at `bytes` (the FMI contract), checked for null.
        unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), bytes as *mut u8, size) };
        OK
    })
}

/// `fmi2DeSerializeFMUstate`.
///
/// # Safety
/// `bytes` points to `size` bytes; `state` points to an `fmi2FMUstate`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut c_void,
    bytes: *const c_char,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    with_instance(c, |inst| {
        // SAFETY: `size` bytes (checked for null).
        let Some(data) = (unsafe { slice(bytes as *const u8, size) }) else {
            return inst.status("fmi2DeSerializeFMUstate", Err("bytes is null".into()));
        };
        if state.is_null() {
            return inst.status("fmi2DeSerializeFMUstate", Err("FMUstate is null".into()));
        }
        match inst.slave.deserialize(data) {
            Ok(s) => {
                // SAFETY: checked for null.
                let slot = unsafe { &mut *state };
                let existing = *slot as *mut Slave;
                if !existing.is_null() && inst.states.contains(&existing) {
                    // SAFETY: a state this instance handed out and has not freed.
                    unsafe { *existing = s };
                } else {
                    let p = Box::into_raw(Box::new(s));
                    inst.states.push(p);
                    *slot = p as *mut c_void;
                }
                OK
            }
            Err(e) => inst.status("fmi2DeSerializeFMUstate", Err(e)),
        }
    })
}

/// `fmi2GetStatus` (and the typed variants): no asynchronous step, so nothing to report.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStatus(c: *mut c_void, _s: c_int, _value: *mut c_int) -> Status {
    with_instance(c, |inst| unsupported(inst, "fmi2GetStatus"))
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` is the FMU's time.
///
/// # Safety
/// `value` points to a double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: *mut c_void, s: c_int, value: *mut f64) -> Status {
    with_instance(c, |inst| {
        if s != 2 || value.is_null() {
            return unsupported(
                inst,
                "fmi2GetRealStatus (other than fmi2LastSuccessfulTime)",
            );
        }
        // SAFETY: checked for null.
        unsafe { *value = inst.slave.time() };
        OK
    })
}

fn unsupported(inst: &mut Instance, what: &str) -> Status {
    inst.status(what, Err("not supported by this FMU".into()))
}

macro_rules! unsupported_fns {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: not supported (fmi2Error with a message).")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(c: *mut c_void, $($arg: $ty),*) -> Status {
            $(let _ = $arg;)*
            with_instance(c, |inst| unsupported(inst, stringify!($name)))
        }
    )*};
}

unsupported_fns! {
    fmi2GetInteger(vr: *const c_uint, n: usize, value: *mut c_int);
    fmi2GetBoolean(vr: *const c_uint, n: usize, value: *mut c_int);
    fmi2GetString(vr: *const c_uint, n: usize, value: *mut *const c_char);
    fmi2SetInteger(vr: *const c_uint, n: usize, value: *const c_int);
    fmi2SetBoolean(vr: *const c_uint, n: usize, value: *const c_int);
    fmi2SetString(vr: *const c_uint, n: usize, value: *const *const c_char);
    fmi2GetDirectionalDerivative(u: *const c_uint, nu: usize, z: *const c_uint, nz: usize, dv: *const f64, dz: *mut f64);
    fmi2GetRealOutputDerivatives(vr: *const c_uint, n: usize, order: *const c_int, value: *mut f64);
    fmi2GetIntegerStatus(s: c_int, value: *mut c_int);
    fmi2GetBooleanStatus(s: c_int, value: *mut c_int);
    fmi2GetStringStatus(s: c_int, value: *mut *const c_char);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris_become_paths() {
        assert_eq!(
            uri_to_path("file:///tmp/a%20b/resources").unwrap(),
            std::path::PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(
            uri_to_path("file:/tmp/x").unwrap(),
            std::path::PathBuf::from("/tmp/x")
        );
        assert_eq!(
            uri_to_path("file://localhost/tmp/x").unwrap(),
            std::path::PathBuf::from("/tmp/x")
        );
        assert!(uri_to_path("http://x").is_none());
        assert!(uri_to_path("file:///a%zz").is_none());
    }

    #[test]
    fn null_and_unknown_handles_are_errors_not_crashes() {
        assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 1e-3, 0), ERROR);
        // SAFETY: null arguments are what is being tested.
        let c = unsafe {
            fmi2Instantiate(
                std::ptr::null(),
                1,
                std::ptr::null(),
                std::ptr::null(),
                std::ptr::null(),
                0,
                0,
            )
        };
        assert!(c.is_null());
    }
}
