//! One list of every device backend palpus can open, as CHAI3D's `cHapticDeviceHandler` lists
//! every vendor's devices: scenes, `palpus run`, `palpus capture` and `palpus devices` read it,
//! so adding a vendor is one file that defines its [`Backend`] and one line in [`BUILTIN`].
//!
//! A device is named on the command line and in scenes as `NAME` or `NAME:OPTION`; what the
//! option means is the backend's (the Omega.7's SDK library, the capture a replay plays).

use capture::CaptureKind;

use super::backend::{Backend, OpenRequest, OpenedDevice, SimSetup};
use super::{omega7, replay, sim_omega7};
use crate::error::HapticsError;

/// Every backend palpus ships, in the order `palpus devices` lists them.
pub static BUILTIN: [&Backend; 3] = [&sim_omega7::BACKEND, &omega7::BACKEND, &replay::BACKEND];

/// A backend chosen by name, with its option.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceChoice {
    backend: &'static Backend,
    option: Option<String>,
}

impl DeviceChoice {
    /// The backend.
    pub fn backend(&self) -> &'static Backend {
        self.backend
    }

    /// The option given after the name.
    pub fn option(&self) -> Option<&str> {
        self.option.as_deref()
    }

    /// Opens the device with this choice's option.
    pub fn open(
        &self,
        period_s: f64,
        sim: SimSetup,
        recording_kind: CaptureKind,
    ) -> Result<OpenedDevice, HapticsError> {
        (self.backend.open)(OpenRequest {
            period_s,
            option: self.option(),
            sim,
            recording_kind,
        })
    }

    /// The device in a few words, for reports.
    pub fn label(&self) -> String {
        match &self.option {
            Some(option) => format!("{} ({option})", self.backend.summary),
            None => self.backend.summary.to_owned(),
        }
    }
}

/// The backends a program can open.
#[derive(Debug, Clone)]
pub struct Registry {
    backends: Vec<&'static Backend>,
}

impl Default for Registry {
    fn default() -> Self {
        Self::builtin()
    }
}

impl Registry {
    /// The backends palpus ships ([`BUILTIN`]).
    pub fn builtin() -> Self {
        Self {
            backends: BUILTIN.to_vec(),
        }
    }

    /// This registry with `backend` added after the others, or in place of the one of its name.
    pub fn with(mut self, backend: &'static Backend) -> Self {
        match self.backends.iter_mut().find(|b| b.name == backend.name) {
            Some(slot) => *slot = backend,
            None => self.backends.push(backend),
        }
        self
    }

    /// Every backend, in order.
    pub fn backends(&self) -> &[&'static Backend] {
        &self.backends
    }

    /// The backend named `name`.
    pub fn get(&self, name: &str) -> Option<&'static Backend> {
        self.backends.iter().copied().find(|b| b.name == name)
    }

    /// The names, for messages: `sim, omega7[:PATH], replay:FILE`.
    pub fn names(&self) -> String {
        let name = |b: &&Backend| match b.option {
            Some(o) if o.required => format!("{}:{}", b.name, o.value_name),
            Some(o) => format!("{}[:{}]", b.name, o.value_name),
            None => b.name.to_owned(),
        };
        self.backends.iter().map(name).collect::<Vec<_>>().join(", ")
    }

    /// Reads `NAME` or `NAME:OPTION`.
    pub fn choose(&self, text: &str) -> Result<DeviceChoice, HapticsError> {
        let (name, option) = match text.split_once(':') {
            Some((name, option)) => (name, Some(option)),
            None => (text, None),
        };
        let unknown = |reason: &str| HapticsError::UnknownDevice {
            given: text.chars().take(200).collect(),
            reason: reason.to_owned(),
            expected: self.names(),
        };
        let backend = self.get(name).ok_or_else(|| unknown("no device of that name"))?;
        match (backend.option, option) {
            (None, Some(_)) => Err(unknown("this device takes no option")),
            (Some(o), None) if o.required => Err(unknown(&format!("this device needs its {}", o.value_name))),
            (Some(o), Some("")) => Err(unknown(&format!("the {} is empty", o.value_name))),
            _ => Ok(DeviceChoice {
                backend,
                option: option.map(str::to_owned),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_read_back() {
        let registry = Registry::builtin();
        for backend in registry.backends() {
            assert_eq!(registry.get(backend.name), Some(*backend));
            assert_eq!(
                registry
                    .backends()
                    .iter()
                    .filter(|b| b.name == backend.name)
                    .count(),
                1
            );
        }
        assert_eq!(registry.choose("sim").unwrap().backend().name, "sim");
        let replay = registry.choose("replay:a:b.csv").unwrap();
        assert_eq!(replay.option(), Some("a:b.csv"));
    }

    #[test]
    fn a_bad_name_or_option_names_every_device() {
        let registry = Registry::builtin();
        for bad in ["phantom", "sim:x", "replay", "replay:", ""] {
            let e = registry.choose(bad).unwrap_err().to_string();
            assert!(e.contains("sim, omega7[:PATH], replay:FILE"), "{bad}: {e}");
        }
    }
}
