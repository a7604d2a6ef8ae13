//! The facts `hapticlab doctor` judges, read from the system once: USB
//! Falcons, the firmware file, resource limits and capabilities, the
//! terminal, the dataset folder. Reading them is all this file does; the
//! verdicts are the pure functions in `doctor.rs`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use super::Needs;
use crate::clock;
use crate::device::falcon::firmware::{self, FirmwareFileError};
use crate::device::falcon::usb::{self, FalconInfo, UsbError};

/// Everything the checks look at.
#[derive(Debug, Clone)]
pub struct Facts {
    /// Effective user id 0.
    pub root: bool,
    pub usb: Result<Vec<FalconInfo>, UsbError>,
    /// An installed udev rule naming the Falcon (0403:cb48), if any.
    pub udev_rule: Option<PathBuf>,
    /// The group the shipped rule falls back on exists on this system.
    pub udev_group: bool,
    /// The profile's firmware file through the driver's validation (its
    /// length when good); `None` when the profile names none.
    pub firmware: Option<Result<usize, FirmwareFileError>>,
    pub system: SystemFacts,
    pub terminal: TerminalFacts,
    pub dataset: DatasetFacts,
}

/// A resource limit; `None` is unlimited.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limit {
    pub soft: Option<u64>,
    pub hard: Option<u64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct SystemFacts {
    pub rtprio: Limit,
    /// Bytes.
    pub memlock: Limit,
    pub cap_sys_nice: bool,
    pub cap_ipc_lock: bool,
    /// The cores this process may run on.
    pub allowed_cpus: Vec<usize>,
    /// This process's mapped memory (VmSize), bytes.
    pub vm_bytes: Option<u64>,
    /// SCHED_FIFO at the asked priority, tried on a scratch thread (when asked).
    pub fifo_trial: Option<Result<(), String>>,
    /// Pinning a scratch thread to the asked core (when asked).
    pub pin_trial: Option<Result<(), String>>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TerminalFacts {
    pub stdout_is_terminal: bool,
    /// Columns × rows, when a terminal.
    pub size: Option<(u16, u16)>,
    pub term: Option<String>,
    pub colorterm: Option<String>,
    /// NO_COLOR set and not empty (no-color.org; crossterm honours it).
    pub no_color: bool,
}

/// Whether the dataset folder is there.
#[derive(Debug, Clone, PartialEq)]
pub enum DirState {
    Exists,
    /// Not there; `ancestor` is the nearest folder above it that is.
    Missing {
        ancestor: PathBuf,
    },
    /// The path, or a folder on the way to it, is a file.
    NotADirectory {
        blocker: PathBuf,
    },
    /// The path, or a folder on the way to it, is a symlink that leads
    /// nowhere: nothing can be made there (the console refuses it too).
    DanglingLink {
        link: PathBuf,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct DatasetFacts {
    pub dir: PathBuf,
    pub state: DirState,
    /// A temporary file created and removed in the folder (or, when it is
    /// missing, in the ancestor it would be created in).
    pub write: Result<(), String>,
    /// Free bytes for an unprivileged user on the folder's filesystem.
    pub free_bytes: Option<u64>,
    /// That filesystem is mounted read-only.
    pub read_only: bool,
}

impl Facts {
    pub fn gather(needs: &Needs, dataset: &Path) -> Facts {
        Facts {
            root: is_root(),
            usb: usb::list_falcons(),
            udev_rule: find_udev_rule(),
            udev_group: group_exists(usb::UDEV_GROUP),
            firmware: needs
                .firmware
                .as_deref()
                .map(|p| firmware::load_image(p).map(|img| img.bytes.len())),
            system: SystemFacts::gather(needs),
            terminal: TerminalFacts::gather(),
            dataset: DatasetFacts::gather(dataset),
        }
    }
}

fn is_root() -> bool {
    // SAFETY: geteuid takes nothing and cannot fail.
    unsafe { libc::geteuid() == 0 }
}

/// Folders udev reads rules from.
const UDEV_RULE_DIRS: [&str; 4] = [
    "/etc/udev/rules.d",
    "/run/udev/rules.d",
    "/usr/lib/udev/rules.d",
    "/lib/udev/rules.d",
];

fn find_udev_rule() -> Option<PathBuf> {
    UDEV_RULE_DIRS.iter().find_map(|d| {
        std::fs::read_dir(d).ok()?.flatten().find_map(|e| {
            let path = e.path();
            let text = std::fs::read_to_string(&path).ok()?;
            rule_names_falcon(&text).then_some(path)
        })
    })
}

/// Whether `/etc/group` lists `name` (the groups udev can use are local).
fn group_exists(name: &str) -> bool {
    std::fs::read_to_string("/etc/group")
        .is_ok_and(|t| t.lines().any(|l| l.split(':').next() == Some(name)))
}

/// Whether udev rules text gives the Falcon (0403:cb48) a rule (comments aside).
pub fn rule_names_falcon(text: &str) -> bool {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.starts_with('#'))
        .any(|l| l.contains("\"0403\"") && l.to_ascii_lowercase().contains("\"cb48\""))
}

/// A limit read by `get` (a `getrlimit` call on a resource).
fn limit(get: impl FnOnce(&mut libc::rlimit) -> libc::c_int) -> Limit {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    if get(&mut r) != 0 {
        return Limit {
            soft: Some(0),
            hard: Some(0),
        };
    }
    let v = |x: libc::rlim_t| (x != libc::RLIM_INFINITY).then_some(x);
    Limit {
        soft: v(r.rlim_cur),
        hard: v(r.rlim_max),
    }
}

/// Capability bits from `/proc/self/status`.
const CAP_IPC_LOCK: u32 = 14;
const CAP_SYS_NICE: u32 = 23;

/// The effective capability set from `/proc/self/status` text.
pub fn effective_caps(status: &str) -> u64 {
    status
        .lines()
        .find_map(|l| l.strip_prefix("CapEff:"))
        .and_then(|v| u64::from_str_radix(v.trim(), 16).ok())
        .unwrap_or(0)
}

/// `VmSize` from `/proc/self/status` text, in bytes.
pub fn vm_size(status: &str) -> Option<u64> {
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmSize:"))?
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse::<u64>()
        .ok()?;
    Some(kb * 1024)
}

fn allowed_cpus() -> Vec<usize> {
    // SAFETY: a zeroed cpu_set_t is valid; sched_getaffinity fills it;
    // CPU_ISSET reads within it for i < CPU_SETSIZE.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
            let n = std::thread::available_parallelism().map_or(1, |n| n.get());
            return (0..n).collect();
        }
        (0..libc::CPU_SETSIZE as usize)
            .filter(|&i| libc::CPU_ISSET(i, &set))
            .collect()
    }
}

impl SystemFacts {
    pub fn gather(needs: &Needs) -> SystemFacts {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        let caps = effective_caps(&status);
        // The servo's own calls, on a thread that exits at once.
        let (fifo_trial, pin_trial) = match &needs.realtime {
            None => (None, None),
            Some(rt) => {
                let (priority, cpu) = (rt.priority, rt.cpu);
                std::thread::spawn(move || {
                    (
                        Some(clock::set_fifo_priority(priority).map_err(|e| e.to_string())),
                        cpu.map(|c| clock::pin_to_cpu(c).map_err(|e| e.to_string())),
                    )
                })
                .join()
                .unwrap_or((None, None))
            }
        };
        SystemFacts {
            // SAFETY: getrlimit writes into the rlimit it is given.
            rtprio: limit(|r| unsafe { libc::getrlimit(libc::RLIMIT_RTPRIO, r) }),
            // SAFETY: as above.
            memlock: limit(|r| unsafe { libc::getrlimit(libc::RLIMIT_MEMLOCK, r) }),
            cap_sys_nice: caps & (1 << CAP_SYS_NICE) != 0,
            cap_ipc_lock: caps & (1 << CAP_IPC_LOCK) != 0,
            allowed_cpus: allowed_cpus(),
            vm_bytes: vm_size(&status),
            fifo_trial,
            pin_trial,
        }
    }
}

impl TerminalFacts {
    pub fn gather() -> TerminalFacts {
        let stdout_is_terminal = std::io::stdout().is_terminal();
        let var = |k| std::env::var(k).ok();
        TerminalFacts {
            stdout_is_terminal,
            size: stdout_is_terminal
                .then(|| ratatui::crossterm::terminal::size().ok())
                .flatten(),
            term: var("TERM"),
            colorterm: var("COLORTERM"),
            no_color: var("NO_COLOR").is_some_and(|v| !v.is_empty()),
        }
    }
}

/// Where `dir` stands: there, missing below an existing folder, or blocked by a file.
pub fn dir_state(dir: &Path) -> DirState {
    // A relative path's ancestors end in "", which is the current folder.
    let mut at = dir;
    loop {
        let probe = if at.as_os_str().is_empty() {
            Path::new(".")
        } else {
            at
        };
        match std::fs::metadata(probe) {
            Ok(m) if m.is_dir() && at == dir => return DirState::Exists,
            Ok(m) if m.is_dir() => {
                return DirState::Missing {
                    ancestor: probe.to_path_buf(),
                };
            }
            Ok(_) => {
                return DirState::NotADirectory {
                    blocker: probe.to_path_buf(),
                };
            }
            Err(_)
                if std::fs::symlink_metadata(probe).is_ok_and(|m| m.file_type().is_symlink()) =>
            {
                return DirState::DanglingLink {
                    link: probe.to_path_buf(),
                };
            }
            Err(_) => match at.parent() {
                Some(up) => at = up,
                None => {
                    return DirState::Missing {
                        ancestor: PathBuf::from("/"),
                    };
                }
            },
        }
    }
}

/// Create and remove a temporary file in `dir`.
fn write_probe(dir: &Path) -> Result<(), String> {
    let path = dir.join(format!(".hapticlab-doctor-{}.tmp", std::process::id()));
    let made = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&path)
        .and_then(|mut f| std::io::Write::write_all(&mut f, b"hapticlab doctor\n"));
    let removed = std::fs::remove_file(&path);
    made.map_err(|e| e.to_string())?;
    removed.map_err(|e| format!("the test file could not be removed: {e}"))
}

/// Free bytes for unprivileged users, and whether it is mounted read-only.
fn filesystem(dir: &Path) -> Option<(u64, bool)> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: a zeroed statvfs is valid; statvfs fills it from a NUL-terminated path.
    unsafe {
        let mut s: libc::statvfs = std::mem::zeroed();
        if libc::statvfs(c.as_ptr(), &mut s) != 0 {
            return None;
        }
        Some((
            s.f_bavail as u64 * s.f_frsize as u64,
            s.f_flag & libc::ST_RDONLY != 0,
        ))
    }
}

impl DatasetFacts {
    pub fn gather(dir: &Path) -> DatasetFacts {
        let state = dir_state(dir);
        let (write, free) = match &state {
            DirState::Exists => (write_probe(dir), filesystem(dir)),
            DirState::Missing { ancestor } => (write_probe(ancestor), filesystem(ancestor)),
            DirState::NotADirectory { blocker: b } | DirState::DanglingLink { link: b } => (
                Err(format!("{} is not a folder", b.display())),
                b.parent().and_then(|p| {
                    filesystem(if p.as_os_str().is_empty() {
                        Path::new(".")
                    } else {
                        p
                    })
                }),
            ),
        };
        DatasetFacts {
            dir: dir.to_path_buf(),
            state,
            write,
            free_bytes: free.map(|(bytes, _)| bytes),
            read_only: free.is_some_and(|(_, ro)| ro),
        }
    }
}
