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
//! with extra HALCMD lines); `HOME` is the run's folder (LinuxCNC writes its
//! logs there on failure); as root, `rtapi_app` needs a fallback user (`RTAPI_UID`, not 0)
//! and a FIFO path it can write.

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

/// Homes every joint, then runs each argument as an MDI command and prints, once motion has
/// stopped, `POSE <joints> | <position>` (mm and deg).
const PROBE: &str = r#"
import linuxcnc, sys, time
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
def still():
    for _ in range(600):
        poll()
        if s.interp_state == linuxcnc.INTERP_IDLE and s.queue == 0 and s.inpos: return
        time.sleep(0.05)
    raise SystemExit("motion did not stop")
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
c.mode(linuxcnc.MODE_MDI); wait()
for cmd in sys.argv[1:]:
    c.mdi(cmd); wait(); time.sleep(0.2); still()
    j = " ".join(repr(v) for v in s.joint_actual_position[:s.joints])
    p = " ".join(repr(v) for v in s.actual_position[:9])
    print("POSE", j, "|", p, flush=True)
"#;

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

/// The sample's ini text made headless (see the module's doc).
fn headless_ini(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
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

/// A sample's HAL file made headless: the vismach model's `loadusr -W`, and its pins (words
/// with `gui.`) left out of `setp` and `net` lines, with an arrow left pointing at nothing.
fn headless_hal(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("loadusr -W") || (t.starts_with("setp") && t.contains("gui.")) {
            continue;
        }
        if t.starts_with("net") && t.contains("gui.") {
            let mut kept: Vec<&str> = t
                .split_whitespace()
                .filter(|w| !w.contains("gui."))
                .collect();
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
    std::fs::write(dir.join("probe.py"), PROBE).unwrap();
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
    /// Homes, runs `commands` by MDI, and returns the pose after each.
    pub fn mdi(&self, commands: &[&str]) -> Vec<Pose> {
        // The same environment as LinuxCNC's own programs (its status buffer and tool
        // data are shared with the fallback user's processes).
        let mut c = Command::new("/usr/bin/python3");
        c.arg(self.dir.join("probe.py"))
            .args(commands)
            .current_dir(&self.dir)
            .env("HOME", &self.dir)
            .env("RTAPI_FIFO_PATH", self.dir.join(".fifo"));
        if let Some(uid) = &self.fallback_uid {
            c.env("RTAPI_UID", uid);
        }
        let out = c.output().expect("python3 runs");
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
