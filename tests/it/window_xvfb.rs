//! The window driven by a user's hand, as far as a test can be one: `palpus run` opens its window
//! on an X display, the test sends the X server real pointer input through the XTEST extension
//! (a drag down over the 3-D view, then the wheel), and the session must report a puncture and
//! write its exit screenshot.
//!
//! What is exercised: X input events reach winit and the window's own drag and wheel handling,
//! which move the simulated hand on the haptic thread; the haptic loop, the puncture analysis and
//! the screenshot on exit. What is not: a window manager and a physical pointer.
//!
//! Without DISPLAY the test starts its own Xvfb on a free display number; when Xvfb is not
//! installed it says so and passes.
#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

use crate::common::text;

/// An Xvfb started by the test, killed when dropped.
struct Xvfb(Child);

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn socket(display: u32) -> PathBuf {
    PathBuf::from(format!("/tmp/.X11-unix/X{display}"))
}

/// Starts Xvfb on the first display number without a lock or socket, and waits for its socket.
fn start_xvfb() -> Option<(Xvfb, u32)> {
    for display in 90..160u32 {
        if Path::new(&format!("/tmp/.X{display}-lock")).exists() || socket(display).exists() {
            continue;
        }
        let child = match Command::new("Xvfb")
            .args([
                &format!(":{display}"),
                "-screen",
                "0",
                "1280x800x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
        {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
            Err(e) => panic!("starting Xvfb: {e}"),
        };
        let mut xvfb = Xvfb(child);
        let deadline = Instant::now() + Duration::from_secs(15);
        while Instant::now() < deadline {
            if UnixStream::connect(socket(display)).is_ok() {
                return Some((xvfb, display));
            }
            // Another server took the number first: try the next one.
            if xvfb.0.try_wait().unwrap().is_some() {
                break;
            }
            sleep(Duration::from_millis(50));
        }
    }
    panic!("no Xvfb display could be started on :90..:159");
}

/// Just enough of the X11 protocol to send XTEST input: connection setup without
/// authorization (a local Xvfb started without -auth accepts it) and FakeInput requests.
struct XTest {
    stream: UnixStream,
    opcode: u8,
}

impl XTest {
    fn connect(display: u32) -> Self {
        let mut stream = UnixStream::connect(socket(display)).unwrap();
        // Little-endian, protocol 11.0, no authorization.
        stream
            .write_all(&[b'l', 0, 11, 0, 0, 0, 0, 0, 0, 0, 0, 0])
            .unwrap();
        let mut head = [0u8; 8];
        stream.read_exact(&mut head).unwrap();
        let extra = u16::from_le_bytes([head[6], head[7]]) as usize * 4;
        let mut rest = vec![0u8; extra];
        stream.read_exact(&mut rest).unwrap();
        assert_eq!(head[0], 1, "the X server refused the connection");
        // QueryExtension "XTEST".
        let name = b"XTEST";
        let mut request = vec![98, 0, 4, 0, name.len() as u8, 0, 0, 0];
        request.extend_from_slice(name);
        request.extend_from_slice(&[0, 0, 0]);
        stream.write_all(&request).unwrap();
        let mut reply = [0u8; 32];
        stream.read_exact(&mut reply).unwrap();
        assert!(reply[0] == 1 && reply[8] == 1, "the X server has no XTEST");
        XTest {
            stream,
            opcode: reply[9],
        }
    }

    /// FakeInput: `kind` 4/5 button press/release (`detail` the button), 6 motion to (x, y).
    fn fake(&mut self, kind: u8, detail: u8, x: i16, y: i16) {
        let mut r = vec![self.opcode, 2, 9, 0, kind, detail, 0, 0];
        r.extend_from_slice(&[0; 4]); // time: now
        r.extend_from_slice(&[0; 4]); // root: the pointer's screen
        r.extend_from_slice(&[0; 8]);
        r.extend_from_slice(&x.to_le_bytes());
        r.extend_from_slice(&y.to_le_bytes());
        r.extend_from_slice(&[0; 8]);
        assert_eq!(r.len(), 36);
        self.stream.write_all(&r).unwrap();
    }

    fn move_to(&mut self, x: i16, y: i16) {
        self.fake(6, 0, x, y);
    }

    fn click(&mut self, button: u8, down: bool) {
        self.fake(if down { 4 } else { 5 }, button, 0, 0);
    }
}

fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

#[test]
fn dragging_and_scrolling_in_the_window_punctures_the_liver() {
    let own_display = std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty());
    let (_xvfb, display) = if own_display {
        match start_xvfb() {
            Some((x, d)) => (Some(x), d),
            None => {
                eprintln!("Xvfb is not installed: the window test needs it (apt-get install xvfb)");
                return;
            }
        }
    } else {
        // A display given by the caller (xvfb-run): its number.
        let d = std::env::var("DISPLAY").unwrap();
        let number = d
            .rsplit(':')
            .next()
            .and_then(|n| n.split('.').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("DISPLAY={d}: expected :N"));
        (None, number)
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let mut app = crate::common::palpus_command()
        // The input below takes about 6.5 s from the window's opening.
        .args(["run", "--duration", "9", "--report", out.to_str().unwrap()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("DISPLAY", format!(":{display}"))
        .env("PALPUS_CACHE_DIR", dir.path().join("cache"))
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The window opens once the scene's models are resolved, right after this line is printed;
    // input sent before it exists would be lost.
    let stdout = app.stdout.take().unwrap();
    let (opened, opened_rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in std::io::BufRead::lines(std::io::BufReader::new(stdout)) {
            let Ok(line) = line else { break };
            if line.contains("in a window") {
                let _ = opened.send(());
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    if opened_rx.recv_timeout(Duration::from_secs(300)).is_err() {
        let _ = app.kill();
        let o = app.wait_with_output().unwrap();
        panic!("the window never opened:\n{}{}", reader.join().unwrap(), text(&o));
    }
    let mut x = XTest::connect(display);
    sleep(Duration::from_secs(2));
    // Drag down over the 3-D view (left of the overlay panel): 10 mm down at 1e-4 m/px.
    x.move_to(400, 250);
    x.click(1, true);
    for step in 1..=20i16 {
        x.move_to(400, 250 + 5 * step);
        sleep(Duration::from_millis(40));
    }
    x.click(1, false);
    // Then the wheel (button 4: away from the user, pushes the tool down, 1 mm a line).
    x.move_to(400, 360);
    for _ in 0..45 {
        x.click(4, true);
        x.click(4, false);
        sleep(Duration::from_millis(80));
    }
    let o = app.wait_with_output().unwrap();
    let printed = format!("{}{}", reader.join().unwrap(), text(&o));
    assert!(o.status.success(), "{printed}");
    assert!(printed.contains("in a window"), "{printed}");
    eprintln!("{printed}");
    let r = report(&out);
    let seg = &r["segments"][0];
    let punctures = seg["punctures"].as_array().unwrap();
    assert!(!punctures.is_empty(), "no puncture reported: {seg}");
    assert!(printed.contains("puncture 1 at"), "{printed}");
    let shot = render::Image::load_png(&out.join("window.png")).unwrap();
    assert!(
        shot.width >= 640 && shot.height >= 400,
        "{}x{}",
        shot.width,
        shot.height
    );
    // The window reports how steadily it drew.
    assert!(printed.contains("frame time p50"), "{printed}");
}
