//! A foreign log through `import` with one of several column maps (the first byte picks it):
//! an error or a capture, never a panic.
#![no_main]

use std::sync::OnceLock;

use capture::CaptureKind;
use capture::{ColumnMap, ImportSpec, import_csv};
use libfuzzer_sys::fuzz_target;

fn specs() -> &'static [ImportSpec] {
    static SPECS: OnceLock<Vec<ImportSpec>> = OnceLock::new();
    SPECS.get_or_init(|| {
        let spec = |kind, map: &str, rate: Option<f64>, input_rate: Option<f64>| {
            let mut s = ImportSpec::new(kind, ColumnMap::parse(map).expect("a valid map"));
            s.rate_hz = rate;
            s.input_rate_hz = input_rate;
            s
        };
        vec![
            spec(
                CaptureKind::Rubbing,
                "time_s=t_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=Fn,friction_force_n=Ff",
                None,
                None,
            ),
            spec(
                CaptureKind::Rubbing,
                "time_s=t_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=Fn,friction_force_n=Ff",
                Some(250.0),
                None,
            ),
            spec(
                CaptureKind::Rubbing,
                "tangential_position_m=x_mm[mm],normal_force_n=Fn,friction_force_n=Ff",
                Some(100.0),
                Some(1000.0),
            ),
            spec(
                CaptureKind::Insertion,
                "time_s=t,depth_m=depth[mm],axial_force_n=F",
                Some(1000.0),
                None,
            ),
        ]
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else {
        return;
    };
    // One file per process: libFuzzer runs one input at a time.
    let path = std::env::temp_dir().join(format!("palpus-fuzz-import-{}.csv", std::process::id()));
    if std::fs::write(&path, bytes).is_err() {
        return;
    }
    let specs = specs();
    let _ = import_csv(&path, &specs[usize::from(pick) % specs.len()]);
});
