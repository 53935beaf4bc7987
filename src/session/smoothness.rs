//! How smooth a movement was: the spectral arc length (SPARC) of its speed profile.
//!
//! Balasubramanian, Melendez-Calderon, Roby-Brami & Burdet, "On the analysis of movement
//! smoothness", J. NeuroEng. Rehabil. 12:112 (2015): the arc length of the speed profile's
//! normalised Fourier magnitude up to an adaptive cutoff (at most 10 Hz, where the magnitude
//! last reaches 5 %). It is dimensionless (the same for a movement scaled in amplitude or
//! stretched in time), about −1.4 for one minimum-jerk reach and more negative the more
//! submovements, pauses or tremor the movement has; unlike jerk-based measures it does not
//! grow with the sensor's noise. Written here because no crate computes it; checked against
//! the authors' published implementation (`scripts/sparc_reference.py`).

/// Zero-padding of the transform: the next power of two above the profile, times 2⁴.
const PAD_LEVEL: u32 = 4;
/// The highest frequency a voluntary movement's spectrum is read to, Hz.
const CUTOFF_HZ: f64 = 10.0;
/// The normalised magnitude below which the spectrum's ends are cut off.
const AMPLITUDE_THRESHOLD: f64 = 0.05;

/// SPARC of `speed` (m/s, or any unit: it is normalised) sampled at `rate_hz`; `None` when the
/// profile is too short, never moves, or is not finite.
pub fn sparc(speed: &[f64], rate_hz: f64) -> Option<f64> {
    if speed.len() < 2 || !(rate_hz.is_finite() && rate_hz > 0.0) || speed.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let nfft = speed.len().checked_next_power_of_two()?.checked_shl(PAD_LEVEL)?;
    let plan = fft::forward_plan(nfft);
    let mut input = vec![0.0; nfft];
    input[..speed.len()].copy_from_slice(speed);
    let mut spectrum = plan.make_output_vec();
    plan.process(&mut input, &mut spectrum).ok()?;
    let magnitude: Vec<f64> = spectrum.iter().map(|c| c.norm()).collect();
    // The largest magnitude of the whole (symmetric) spectrum is in its first half.
    let peak = magnitude.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return None;
    }
    let step_hz = rate_hz / nfft as f64;
    let within = magnitude
        .iter()
        .enumerate()
        .take_while(|&(k, _)| k as f64 * step_hz <= CUTOFF_HZ)
        .map(|(_, m)| m / peak);
    let selected: Vec<f64> = within.collect();
    let first = selected.iter().position(|&m| m >= AMPLITUDE_THRESHOLD)?;
    let last = selected.iter().rposition(|&m| m >= AMPLITUDE_THRESHOLD)?;
    if last == first {
        return None;
    }
    let band = &selected[first..=last];
    let df = 1.0 / (last - first) as f64;
    Some(-band.windows(2).map(|w| df.hypot(w[1] - w[0])).sum::<f64>())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reach(t: f64, start: f64, duration: f64) -> f64 {
        let tau = ((t - start) / duration).clamp(0.0, 1.0);
        30.0 * tau * tau * (1.0 - tau) * (1.0 - tau)
    }

    fn profile(name: &str, n: usize, rate_hz: f64) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 / rate_hz;
                match name {
                    "minimum_jerk" => reach(t, 0.0, 1.0),
                    "two_submovements" => reach(t, 0.0, 0.6) + reach(t, 0.5, 0.6),
                    "tremor" => reach(t, 0.0, 1.0) + 0.1 * (2.0 * std::f64::consts::PI * 7.0 * t).sin(),
                    other => panic!("no profile {other}"),
                }
            })
            .collect()
    }

    #[test]
    fn sparc_is_the_published_implementations() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/score/sparc.json");
        let fixture: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).expect("fixture")).expect("json");
        let fixture = fixture.as_object().expect("profiles");
        assert_eq!(fixture.len(), 3);
        for (name, v) in fixture {
            let (n, rate_hz) = (
                v["samples"].as_u64().expect("n") as usize,
                v["rate_hz"].as_f64().expect("rate"),
            );
            let want = v["sparc"].as_f64().expect("sparc");
            let got = sparc(&profile(name, n, rate_hz), rate_hz).expect("a movement");
            assert!((got - want).abs() < 1e-9, "{name}: {got} vs {want}");
        }
    }

    #[test]
    fn sparc_is_dimensionless_and_orders_smoothness() {
        let one = sparc(&profile("minimum_jerk", 1000, 1000.0), 1000.0).expect("reach");
        // Ten times faster and sampled twice as often: the same shape, the same value.
        let scaled: Vec<f64> = profile("minimum_jerk", 2000, 2000.0)
            .iter()
            .map(|v| 10.0 * v)
            .collect();
        assert!((sparc(&scaled, 2000.0).expect("reach") - one).abs() < 1e-3);
        let two = sparc(&profile("two_submovements", 1100, 1000.0), 1000.0).expect("reaches");
        assert!(two < one - 0.5, "{two} vs {one}");
        assert_eq!(sparc(&[0.0; 100], 1000.0), None);
        assert_eq!(sparc(&[1.0, f64::NAN], 1000.0), None);
        assert_eq!(sparc(&[1.0], 1000.0), None);
    }
}
