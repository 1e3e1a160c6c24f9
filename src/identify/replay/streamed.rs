//! Replay of a long record in bounded memory, for `seat-twin replay`.

use super::{MetricOptions, StepRule, record_platform, replay_samples};
use crate::dataset::Record;
use crate::dsp::{filtered_derivative, lowpass, rms};
use crate::identify::IdentifyError;
use crate::params::Params;
use crate::simulation::Sample;
use std::sync::Arc;

/// Errors of a streamed replay ([`replay_streamed`]): the channel errors `seat-twin replay`
/// prints, computed as [`super::ChannelErrors`] computes them over the whole record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamedErrors {
    /// Samples replayed.
    pub samples: usize,
    /// RMS error of the filtered relative velocity [m/s] ([`super::ChannelErrors::du`]).
    pub du: f64,
    /// The same divided by the RMS of the measured filtered velocity [-].
    pub du_nrmse: f64,
    /// RMS error of the relative displacement \[m\] ([`super::ChannelErrors::u`]).
    pub u: f64,
    /// RMS error of the filtered body acceleration [m/s²], if measured.
    pub ydd: Option<f64>,
    /// The same errors up to the measured stroke's first end-stop contact, when it has one.
    pub before_end_stop: Option<BeforeEndStop>,
}

/// The errors of a replay up to the measured stroke's first end-stop contact
/// ([`crate::identify::data::first_end_stop_contact`]): the part of the record a calibration
/// fits and replays. After the contact the error is mostly the stop's impact, which the twin
/// takes a little sooner, later or not at all with the smallest change of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeforeEndStop {
    /// Time of the contact from the record's start \[s\].
    pub at_s: f64,
    /// Samples before the contact.
    pub samples: usize,
    /// RMS error of the relative displacement over those samples \[m\].
    pub u: f64,
    /// RMS error of the filtered body acceleration over those samples [m/s²], if measured.
    pub ydd: Option<f64>,
}

/// [`crate::identify::replay()`] of a long record in bounded memory: every sample of the twin goes to `sample`
/// with the record's own time as it is made (for a CSV written row by row), and only what the
/// errors need is kept (the twin's `u`, and `ÿ` when the record has it), so the peak is the
/// record's columns plus about four values a row. Same run, same numbers as [`crate::identify::replay()`].
pub fn replay_streamed(
    params: &Params,
    mut record: Record,
    opt: &MetricOptions,
    mut sample: impl FnMut(f64, &Sample),
) -> Result<StreamedErrors, IdentifyError> {
    params.validate()?;
    let missing = |col: &str| IdentifyError::MissingColumn {
        file: record.path.clone(),
        column: col.to_string(),
    };
    let v_in = record.v_in.take().ok_or_else(|| missing("v_in"))?;
    let u_meas = record.u.take().ok_or_else(|| missing("u"))?;
    let (dt, len) = (record.dt, record.len());
    let name = record
        .path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| record.path.display().to_string());
    let (platform, _) = record_platform(&record);
    // The platform columns now live in `platform`: drop the record's copies.
    (record.x, record.xdd, record.p1, record.p2) = (None, None, None, None);
    let keep_ydd = record.ydd.is_some();
    let mut u_sim = Vec::with_capacity(len);
    let mut ydd_sim = Vec::with_capacity(if keep_ydd { len } else { 0 });
    let mut i = 0;
    // The twin's u and ÿ as the calibrated sensors read them, as in `PreparedRecord::simulate`.
    let mut stroke = params.sensors.u_reader(dt);
    replay_samples(
        params,
        StepRule::Resolving,
        dt,
        Arc::new(v_in),
        platform,
        len,
        &name,
        &mut |s| {
            let mut read = s;
            read.u = stroke.read(s.u);
            read.ydd = params.sensors.read_ydd_sample(s.ydd);
            sample(record.t[i], &read);
            u_sim.push(read.u);
            if keep_ydd {
                ydd_sim.push(read.ydd);
            }
            i += 1;
        },
    )?;
    let lowpass_hz = opt.lowpass_hz.min(0.4 / dt);
    let diff_rms = |a: &[f64], b: &[f64]| {
        let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
        (sum / a.len().max(1) as f64).sqrt()
    };
    let u = diff_rms(&u_sim, &u_meas);
    // The first end-stop contact and u's error before it (u_meas is dropped below).
    let contact =
        crate::identify::data::first_end_stop_contact(&u_meas, params.plant.cylinder.stroke_m)
            .filter(|&c| c > 0)
            .map(|c| (c, diff_rms(&u_sim[..c], &u_meas[..c])));
    let du_meas_f = filtered_derivative(&u_meas, dt, lowpass_hz);
    drop(u_meas);
    let du_sim_f = filtered_derivative(&u_sim, dt, lowpass_hz);
    drop(u_sim);
    let du = diff_rms(&du_sim_f, &du_meas_f);
    let du_nrmse = du / rms(&du_meas_f).max(1e-12);
    drop((du_sim_f, du_meas_f));
    let ydd_filtered = record.ydd.take().map(|ym| {
        let ym = lowpass(&ym, dt, lowpass_hz);
        (lowpass(&ydd_sim, dt, lowpass_hz), ym)
    });
    let ydd = ydd_filtered.as_ref().map(|(s, m)| diff_rms(s, m));
    let before_end_stop = contact.map(|(c, u)| BeforeEndStop {
        at_s: record.t[c] - record.t[0],
        samples: c,
        u,
        ydd: ydd_filtered
            .as_ref()
            .map(|(s, m)| diff_rms(&s[..c], &m[..c])),
    });
    Ok(StreamedErrors {
        samples: len,
        du,
        du_nrmse,
        u,
        ydd,
        before_end_stop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 21, item 7: the streamed replay (bounded memory) is the same run as the held
    /// one, sample for sample, and gives the same errors bit for bit.
    #[test]
    fn a_streamed_replay_equals_the_held_one() {
        let params = crate::identify::testdata::true_params();
        let rec = crate::identify::testdata::twin_record(&params, 2.0, "a.csv").unwrap();
        let held = crate::identify::replay(&Params::paper(), &rec).unwrap();
        let mut rows = Vec::new();
        let e = replay_streamed(
            &Params::paper(),
            rec.clone(),
            &MetricOptions::default(),
            |t, s| rows.push((t, s.u, s.ydd, s.p1, s.q2)),
        )
        .unwrap();
        assert_eq!(rows.len(), held.sim.t.len());
        for (i, r) in rows.iter().enumerate() {
            let h = &held.sim;
            assert_eq!(
                *r,
                (rec.t[i], h.u[i], h.ydd[i], h.p1[i], h.q2[i]),
                "sample {i}"
            );
        }
        let h = &held.errors;
        assert_eq!(
            (e.du, e.du_nrmse, e.u, e.ydd),
            (h.du, h.du_nrmse, h.u, h.ydd)
        );
        assert_eq!(e.samples, h.samples);
        assert_eq!(e.before_end_stop, None);
    }

    /// A measured stroke that reaches an end stop: the errors up to the contact are those of
    /// the record cut there (the cut a calibration makes), replayed on its own; the stroke's
    /// bit for bit (the twin runs forward in time), the filtered ÿ's to its filter's edge.
    #[test]
    fn errors_up_to_an_end_stop_contact_are_those_of_the_record_cut_there() {
        let params = crate::identify::testdata::true_params();
        let mut rec = crate::identify::testdata::twin_record(&params, 2.0, "a.csv").unwrap();
        let stroke = Params::paper().plant.cylinder.stroke_m;
        let contact = 1500;
        if let Some(u) = rec.u.as_mut() {
            u[contact] = 0.5 * stroke - 0.5e-3;
        }
        let e = replay_streamed(
            &Params::paper(),
            rec.clone(),
            &MetricOptions::default(),
            |_, _| {},
        )
        .unwrap();
        let b = e.before_end_stop.expect("a contact");
        assert_eq!(b.samples, contact);
        assert!((b.at_s - 1.5).abs() < 1e-12, "{}", b.at_s);
        let cut = crate::identify::replay(&Params::paper(), &rec.truncated(contact)).unwrap();
        assert_eq!(b.u, cut.errors.u);
        let (y, yc) = (b.ydd.unwrap(), cut.errors.ydd.unwrap());
        assert!((y / yc - 1.0).abs() < 0.05, "{y} against {yc}");
        // The whole record's errors include the sample at the stop.
        assert!(e.u > b.u);
    }
}
