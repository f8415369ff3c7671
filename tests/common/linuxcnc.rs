//! LinuxCNC 2.9 itself, run headless as a reference (a black box): one of its vismach sample
//! configurations, started with a display that shows nothing, driven by MDI from the
//! system Python's `linuxcnc` module, and read back: for each command, the joint positions
//! and the programmed position LinuxCNC's own kinematics module gives.
//!
//! What makes a sample run headless, learnt by running it (not from its source): the
//! display is replaced by a script that waits for a `stop` file (in the ini and the files it
//! includes); the vismach model (`loadusr -W …gui`), PyVCP panel, post-GUI HAL file, intro
//! graphic and the program to open are left out, with the nets to the model's pins (in the
//! ini's HALCMD lines and in the sample's HAL files; what the model wrote, a test may set
//! with extra HALCMD lines); a sample without a home sequence gets one; `HOME` is the run's
//! folder (LinuxCNC writes its logs there on failure); as root, `rtapi_app` needs a fallback
//! user (`RTAPI_UID`, not 0) and a FIFO path it can write.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Where Debian's linuxcnc-uspace puts the sample configurations.
pub const SAMPLES: &str = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis";

/// The display: says it is up (LinuxCNC starts it last, once task and motion run), then
/// waits until the test says stop. LinuxCNC shuts down when it exits.
const IDLE_DISPLAY: &str = "#!/bin/sh\n# Shows nothing: LinuxCNC runs until this exits.\n\
    here=\"$(dirname \"$0\")\"\ntouch \"$here/ready\"\n\
    while [ ! -e \"$here/stop\" ]; do sleep 0.1; done\n";

/// The scripts' start: the `linuxcnc` module's status and command channels (`poll` retries
/// until the status buffer is valid), then out of E-stop, on, and every joint homed.
const HOME_ALL: &str = r#"
import linuxcnc, sys, time, subprocess
s = linuxcnc.stat(); c = linuxcnc.command()
def poll():
    global s
    for _ in range(300):
        try:
            s.poll(); return
        except Exception as e:
            err = e; time.sleep(0.1); s = linuxcnc.stat()
    raise err
def wait(): c.wait_complete(20)
poll()
c.state(linuxcnc.STATE_ESTOP_RESET); wait()
c.state(linuxcnc.STATE_ON); wait()
c.mode(linuxcnc.MODE_MANUAL); wait()
c.home(-1); wait()
for _ in range(300):
    poll()
    if all(s.homed[:s.joints]): break
    time.sleep(0.1)
else:
    raise SystemExit("not homed")
"#;

/// Homes every joint, then runs each argument as an MDI command and prints, once motion has
/// stopped, `POSE <joints> | <position>` (mm and deg).
const PROBE: &str = r#"
def still():
    for _ in range(600):
        poll()
        if s.interp_state == linuxcnc.INTERP_IDLE and s.queue == 0 and s.inpos: return
        time.sleep(0.05)
    raise SystemExit("motion did not stop")
c.mode(linuxcnc.MODE_MDI); wait()
for cmd in sys.argv[1:]:
    c.mdi(cmd); wait(); time.sleep(0.2); still()
    j = " ".join(repr(v) for v in s.joint_actual_position[:s.joints])
    p = " ".join(repr(v) for v in s.actual_position[:9])
    print("POSE", j, "|", p, flush=True)
"#;

/// Homes every joint, then runs the program file `argv[1]` in auto mode while `halsampler`
/// writes the sampler's rows (the joints' commanded positions every servo period) to
/// `argv[2]`, and stops recording once motion has been still for 0.5 s.
const RUN_PROGRAM: &str = r#"
c.mode(linuxcnc.MODE_AUTO); wait()
out = open(sys.argv[2], "w")
rec = subprocess.Popen(["halsampler", "-c", "0"], stdout=out)
time.sleep(0.5)
c.program_open(sys.argv[1]); wait()
c.auto(linuxcnc.AUTO_RUN, 0); wait()
time.sleep(0.5)
for _ in range(6000):
    poll()
    if s.interp_state == linuxcnc.INTERP_IDLE and s.queue == 0 and s.inpos: break
    time.sleep(0.05)
else:
    raise SystemExit("the program did not end")
time.sleep(0.5)
rec.terminate(); rec.wait(); out.close()
poll()
if s.task_state != linuxcnc.STATE_ON: raise SystemExit("machine left ON")
print("DONE", flush=True)
"#;

/// HAL commands that record the signals `signals` (the joints' commanded positions, e.g.
/// `J0:pos-cmd` in LinuxCNC's `basic_sim`) every servo period with a `sampler`, in order,
/// in thousandths (a `mult2` by 1000 before each, named `recorded-<n>`: `halsampler` prints
/// six decimals, so 1 nm; the samples' `basic_sim` has its own `scale`s, hence not those).
pub fn recording(signals: &[&str]) -> Vec<String> {
    let n = signals.len();
    let mut cmds = vec![
        format!(
            "loadrt mult2 names={}",
            (0..n)
                .map(|j| format!("recorded-{j}"))
                .collect::<Vec<_>>()
                .join(",")
        ),
        format!("loadrt sampler depth=4000 cfg={}", "f".repeat(n)),
    ];
    for (j, signal) in signals.iter().enumerate() {
        cmds.push(format!("addf recorded-{j} servo-thread"));
        cmds.push(format!("setp recorded-{j}.in1 1000"));
        cmds.push(format!("net {signal} => recorded-{j}.in0"));
        cmds.push(format!(
            "net recorded-{j} recorded-{j}.out => sampler.0.pin.{j}"
        ));
    }
    cmds.push("addf sampler.0 servo-thread".to_string());
    cmds
}

/// LinuxCNC runs one at a time on a machine (its real-time module and shared memory are
/// global): this lock file, held by each run, makes other test processes wait for their turn.
fn machine_turn() -> std::fs::File {
    let path = std::env::temp_dir().join("mtsim-tests-linuxcnc.lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .unwrap_or_else(|e| panic!("cannot open the lock file {}: {e}", path.display()));
    file.lock()
        .unwrap_or_else(|e| panic!("cannot lock {}: {e}", path.display()));
    file
}

/// LinuxCNC runs one at a time (it keeps a lock file): held by each run.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A LinuxCNC run, stopped (display told to exit, then killed) when dropped.
pub struct Headless {
    dir: PathBuf,
    child: Child,
    /// `RTAPI_UID` when run as root.
    fallback_uid: Option<String>,
    /// Released (after the drop's stop) for the next run.
    _turn: std::sync::MutexGuard<'static, ()>,
    /// The machine-wide turn: other test processes (a second `cargo test`, say) wait on it.
    _machine_turn: std::fs::File,
}

impl Drop for Headless {
    fn drop(&mut self) {
        let _ = std::fs::write(self.dir.join("stop"), "");
        let end = Instant::now() + Duration::from_secs(30);
        while Instant::now() < end {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Why LinuxCNC cannot be run here, if it cannot: the `linuxcnc` script, the system
/// Python's `linuxcnc` module, or the sample configurations are missing.
pub fn missing() -> Option<String> {
    if Command::new("linuxcnc").arg("-h").output().is_err() {
        return Some("`linuxcnc` is not on PATH (Debian package linuxcnc-uspace)".into());
    }
    let module = Command::new("/usr/bin/python3")
        .args(["-c", "import linuxcnc"])
        .output();
    if !module.is_ok_and(|o| o.status.success()) {
        return Some("/usr/bin/python3 cannot import linuxcnc (linuxcnc-uspace)".into());
    }
    if !Path::new(SAMPLES).is_dir() {
        return Some(format!("the sample configurations are not at {SAMPLES}"));
    }
    None
}

/// LinuxCNC, or None after printing why the test is skipped; panics under `CI`, which
/// installs it.
pub fn require(test: &str) -> bool {
    match missing() {
        None => true,
        Some(why) if std::env::var_os("CI").is_some() => {
            panic!("{test}: LinuxCNC cannot run but CI is set: {why}")
        }
        Some(why) => {
            eprintln!("SKIPPED {test}: {why}");
            false
        }
    }
}

/// The sample's ini text made headless (see the module's doc). A sample without a home
/// sequence (3axis-tutorial: its display homes each joint) gets `HOME_SEQUENCE = 0` on every
/// joint, so that `home all` homes them together (refused otherwise, learnt by running it).
fn headless_ini(text: &str) -> String {
    let sequence = !text.contains("HOME_SEQUENCE");
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if sequence && t.starts_with("[JOINT_") {
            out.push_str(line);
            out.push_str("\nHOME_SEQUENCE = 0\n");
            continue;
        }
        let key = t.split('=').next().unwrap_or("").trim();
        let dropped = [
            "PYVCP",
            "POSTGUI_HALFILE",
            "OPEN_FILE",
            "INTRO_GRAPHIC",
            "INTRO_TIME",
        ];
        if dropped.contains(&key) || t.contains("loadusr -W") {
            continue;
        }
        // An ini of the old format asks a GUI to update it; the samples' are already in the
        // new one (joints and axes), whatever they say.
        if key == "VERSION" {
            out.push_str("VERSION = 1.1\n");
            continue;
        }
        if key == "DISPLAY" {
            out.push_str("DISPLAY = ./idle_display\n");
            continue;
        }
        if t.starts_with("HALCMD") && t.contains("-gui.") {
            let kept: Vec<&str> = t
                .split_whitespace()
                .filter(|w| !w.contains("-gui."))
                .collect();
            out.push_str(&kept.join(" "));
            out.push('\n');
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// A sample's HAL file made headless: the user-space components it waits for (`loadusr -W`:
/// the vismach model, a tool-change dialog), and their pins (words with `gui.` or
/// `<component>.`) left out of `setp` and `net` lines, with an arrow left pointing at nothing.
fn headless_hal(text: &str) -> String {
    let waited: Vec<String> = text
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("loadusr -W"))
        .filter_map(|rest| rest.split_whitespace().next())
        .map(|c| format!("{}.", c.rsplit('/').next().unwrap_or(c)))
        .collect();
    let theirs = |w: &str| w.contains("gui.") || waited.iter().any(|c| w.starts_with(c.as_str()));
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        let pins = t.split_whitespace().any(theirs);
        if t.starts_with("loadusr -W") || (t.starts_with("setp") && pins) {
            continue;
        }
        if t.starts_with("net") && pins {
            let mut kept: Vec<&str> = t.split_whitespace().filter(|w| !theirs(w)).collect();
            while kept.last().is_some_and(|w| *w == "<=" || *w == "=>") {
                kept.pop();
            }
            if kept.len() > 2 {
                out.push_str(&kept.join(" "));
                out.push('\n');
            }
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// The sample's HAL files and included ini parts in `dir` made headless, in place.
fn headless_files(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let path = e.path();
        let edit: fn(&str) -> String = match path.extension().and_then(|x| x.to_str()) {
            Some("hal") => headless_hal,
            Some("inc") => headless_ini,
            _ => continue,
        };
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, edit(&text)).unwrap();
    }
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// Everyone may read and write the run's folder (`rtapi_app` runs as the fallback user).
fn open_to_all(path: &Path) {
    use std::os::unix::fs::PermissionsExt;
    let Ok(meta) = std::fs::metadata(path) else {
        return;
    };
    let mode = meta.permissions().mode() | if path.is_dir() { 0o777 } else { 0o666 };
    let _ = std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode));
    if path.is_dir() {
        for e in std::fs::read_dir(path).unwrap().flatten() {
            open_to_all(&e.path());
        }
    }
}

/// Starts the sample `config` (a folder below [`SAMPLES`]) with its `ini` in a fresh copy
/// under `dir`.
pub fn start(config: &str, ini: &str, dir: &Path) -> Headless {
    start_with(config, ini, dir, &[])
}

/// [`start`], with `halcmds` run after the sample's own HAL setup (`[HAL] HALCMD` lines).
pub fn start_with(config: &str, ini: &str, dir: &Path, halcmds: &[&str]) -> Headless {
    let turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let machine_turn = machine_turn();
    let _ = std::fs::remove_dir_all(dir);
    copy_tree(&Path::new(SAMPLES).join(config), dir);
    headless_files(dir);
    let text = std::fs::read_to_string(dir.join(ini)).unwrap();
    let ini_path = dir.join(format!("headless-{ini}"));
    let mut headless = headless_ini(&text);
    if !halcmds.is_empty() {
        let extra: String = halcmds.iter().map(|c| format!("HALCMD = {c}\n")).collect();
        headless = headless.replacen("[HAL]\n", &format!("[HAL]\n{extra}"), 1);
    }
    std::fs::write(&ini_path, headless).unwrap();
    std::fs::write(dir.join("idle_display"), IDLE_DISPLAY).unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        let exec = std::fs::Permissions::from_mode(0o777);
        std::fs::set_permissions(dir.join("idle_display"), exec).unwrap();
    }
    std::fs::write(dir.join("probe.py"), format!("{HOME_ALL}{PROBE}")).unwrap();
    std::fs::write(
        dir.join("run_program.py"),
        format!("{HOME_ALL}{RUN_PROGRAM}"),
    )
    .unwrap();
    open_to_all(dir);
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let mut c = Command::new("linuxcnc");
    c.arg(&ini_path)
        .current_dir(dir)
        .env("HOME", dir)
        .env("RTAPI_FIFO_PATH", dir.join(".fifo"))
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(dir.join("linuxcnc.out")).unwrap())
        .stderr(std::fs::File::create(dir.join("linuxcnc.err")).unwrap());
    let fallback_uid = root.then(|| "65534".to_string());
    if let Some(uid) = &fallback_uid {
        c.env("RTAPI_UID", uid);
    }
    let child = c.spawn().expect("linuxcnc starts");
    let mut run = Headless {
        dir: dir.to_path_buf(),
        child,
        fallback_uid,
        _turn: turn,
        _machine_turn: machine_turn,
    };
    // Up when its display is; a start that fails ends the script first.
    let end = Instant::now() + Duration::from_secs(90);
    while !dir.join("ready").exists() {
        let exited = run.child.try_wait().ok().flatten();
        assert!(
            exited.is_none() && Instant::now() < end,
            "LinuxCNC did not start ({exited:?}): {}",
            std::fs::read_to_string(dir.join("linuxcnc_debug.txt")).unwrap_or_default()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    run
}

/// A pose LinuxCNC reports: joint positions, and the programmed position X Y Z A B C U V W.
#[derive(Clone, Debug)]
pub struct Pose {
    pub joints: Vec<f64>,
    pub position: Vec<f64>,
}

impl Headless {
    /// `script` of the run's folder by the system Python, in LinuxCNC's environment (its
    /// status buffer and tool data are shared with the fallback user's processes).
    fn python(&self, script: &str, args: &[&str]) -> std::process::Output {
        let mut c = Command::new("/usr/bin/python3");
        c.arg(self.dir.join(script))
            .args(args)
            .current_dir(&self.dir)
            .env("HOME", &self.dir)
            .env("RTAPI_FIFO_PATH", self.dir.join(".fifo"));
        if let Some(uid) = &self.fallback_uid {
            c.env("RTAPI_UID", uid);
        }
        c.output().expect("python3 runs")
    }

    /// Homes, runs `program` (G-code text) in auto mode, and returns the joints' commanded
    /// positions every servo period while it ran (a run started with [`recording`]
    /// commands), from 0.5 s before the start to 0.5 s after motion stopped.
    pub fn run_program(&self, name: &str, program: &str) -> Vec<Vec<f64>> {
        let ngc = self.dir.join(format!("{name}.ngc"));
        let rows = self.dir.join(format!("{name}.samples"));
        std::fs::write(&ngc, program).unwrap();
        open_to_all(&self.dir);
        let out = self.python(
            "run_program.py",
            &[&ngc.display().to_string(), &rows.display().to_string()],
        );
        assert!(
            out.status.success() && String::from_utf8_lossy(&out.stdout).contains("DONE"),
            "{name}: {}\n{}",
            String::from_utf8_lossy(&out.stderr),
            std::fs::read_to_string(self.dir.join("linuxcnc.err")).unwrap_or_default()
        );
        // In thousandths (see [`recording`]); the last row may be cut short when recording stops.
        let text = std::fs::read_to_string(&rows).unwrap();
        let parsed: Vec<Vec<f64>> = text
            .lines()
            .filter_map(|l| {
                let row: Option<Vec<f64>> = l
                    .split_whitespace()
                    .map(|v| v.parse::<f64>().ok().map(|v| v / 1000.0))
                    .collect();
                row
            })
            .collect();
        let width = parsed.first().map_or(0, Vec::len);
        parsed.into_iter().filter(|r| r.len() == width).collect()
    }

    /// Homes, runs `commands` by MDI, and returns the pose after each.
    pub fn mdi(&self, commands: &[&str]) -> Vec<Pose> {
        let out = self.python("probe.py", commands);
        let text = String::from_utf8_lossy(&out.stdout);
        let log = || {
            let read = |n: &str| std::fs::read_to_string(self.dir.join(n)).unwrap_or_default();
            format!(
                "probe: {}\nlinuxcnc: {}{}{}",
                String::from_utf8_lossy(&out.stderr),
                read("linuxcnc.out"),
                read("linuxcnc.err"),
                read("linuxcnc_debug.txt")
                    .lines()
                    .filter(|l| l.contains("rror") || l.contains("fail"))
                    .collect::<Vec<_>>()
                    .join("\n")
            )
        };
        assert!(out.status.success(), "{}", log());
        let poses: Vec<Pose> = text
            .lines()
            .filter_map(|l| l.strip_prefix("POSE "))
            .map(|l| {
                let (j, p) = l.split_once('|').unwrap();
                let nums = |s: &str| s.split_whitespace().map(|v| v.parse().unwrap()).collect();
                Pose {
                    joints: nums(j),
                    position: nums(p),
                }
            })
            .collect();
        assert_eq!(poses.len(), commands.len(), "{text}\n{}", log());
        poses
    }
}
