//! The farm story on a real SLURM scheduler: a one-node cluster on localhost runs
//! `examples/farm-slurm.sh` as an array, one task is cancelled in the middle of its frames and
//! resubmitted alone the way the example says (`sbatch --array=ID`), and the meshes must then be
//! every frame, byte for byte those of a plain `splash recon` of the same frames.
//!
//! Needs root and Debian's `slurmctld`, `slurmd` and `slurm-client` (`.ci/run` installs them);
//! prints `skipped: <reason>` and returns where it cannot run. The cluster is its own: a
//! `slurm.conf` in a temporary directory (`auth/none`, so no munge), fresh ports, the daemons
//! started in the foreground and killed when the test ends, whatever way it ends.

mod common;

use std::fs;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{entries, fixture};
use serde_json::Value;

/// Array size: tasks 0..TASKS, `--shard auto/TASKS`, two frames each.
const TASKS: u32 = 3;
const FRAMES: u32 = 6;
/// The task that is cancelled and resubmitted: shard 2, frames 2 and 5.
const VICTIM: u32 = 1;
/// The whole test stays under about three minutes; each wait has its own bound below.
const JOB_LIMIT: Duration = Duration::from_secs(100);

/// A command of SLURM's, with the longest it may take (coreutils `timeout`).
fn bounded(program: &Path, seconds: u32) -> Command {
    let mut command = Command::new("timeout");
    command.arg(seconds.to_string()).arg(program);
    command
}

/// The environment without the variables of a SLURM job or of sbatch/srun defaults, so that a
/// test run inside someone's allocation talks to this cluster only.
fn clean_env(command: &mut Command) -> &mut Command {
    for (key, _) in std::env::vars_os() {
        let key = key.to_string_lossy();
        if [
            "SLURM_", "SBATCH_", "SRUN_", "SQUEUE_", "SINFO_", "SCANCEL_",
        ]
        .iter()
        .any(|p| key.starts_with(p))
        {
            command.env_remove(key.as_ref());
        }
    }
    command
}

fn find_program(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/usr/local/sbin", "/usr/bin"].map(PathBuf::from))
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

fn text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// The last `lines` lines of a file, for a failure message.
fn tail(path: &Path, lines: usize) -> String {
    let all = fs::read_to_string(path).unwrap_or_else(|e| format!("({e})\n"));
    let kept: Vec<&str> = all.lines().collect();
    let start = kept.len().saturating_sub(lines);
    format!(
        "--- {} (last {lines} lines)\n{}\n",
        path.display(),
        kept[start..].join("\n")
    )
}

fn free_port() -> u16 {
    TcpListener::bind("0.0.0.0:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Kills `pid` if it is still the program `name` (a pid file may outlive its process).
fn kill_if(pid: u32, name: &str) {
    let comm = fs::read_to_string(format!("/proc/{pid}/comm")).unwrap_or_default();
    if comm.trim() == name {
        kill(pid);
    }
}

fn kill(pid: u32) {
    let _ = Command::new("kill").arg("-9").arg(pid.to_string()).status();
}

/// Whether process `pid` runs (a zombie does not).
fn alive(pid: u32) -> bool {
    fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        // pid (comm) state …: the state follows the last ')'.
        stat.rsplit(')')
            .next()
            .and_then(|rest| rest.trim().chars().next())
            != Some('Z')
    })
}

/// Kills the processes working in the cluster directory `dir` (slurmstepd, the job scripts,
/// srun, splash) or talking to its cluster.
fn kill_jobs(dir: &Path) {
    let conf = format!("SLURM_CONF={}", dir.join("slurm.conf").display());
    for process in fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Ok(pid) = process.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let cwd = fs::read_link(process.path().join("cwd")).unwrap_or_default();
        let environ = fs::read(process.path().join("environ")).unwrap_or_default();
        if pid != std::process::id()
            && (cwd.starts_with(dir)
                || environ.split(|b| *b == 0).any(|var| var == conf.as_bytes()))
        {
            kill(pid);
        }
    }
}

const PREFIX: &str = "splash-slurm-";

/// Daemons, jobs and directories that earlier runs left when they were killed before cleaning
/// up. A directory whose test process is gone has its daemons killed by their pid files, the
/// processes working in it (slurmstepd, the job scripts, srun, splash) or talking to its
/// cluster killed too, and is removed. Directories of live test processes (a concurrent run)
/// are left alone; every run has its own ports, so those do not clash.
fn remove_stale_clusters() {
    let Ok(read) = fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for entry in read.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(owner) = name
            .strip_prefix(PREFIX)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if owner == std::process::id() || alive(owner) {
            continue;
        }
        let dir = entry.path();
        for daemon in ["slurmctld", "slurmd"] {
            let pid_file = dir.join(format!("{daemon}.pid"));
            if let Some(pid) = fs::read_to_string(pid_file)
                .ok()
                .and_then(|p| p.trim().parse().ok())
            {
                kill_if(pid, daemon);
            }
        }
        kill_jobs(&dir);
        let _ = fs::remove_dir_all(dir);
    }
}

/// A one-node cluster on localhost, stopped (jobs cancelled, daemons killed) when dropped.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    sbin: [PathBuf; 2],
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    /// Starts the cluster and waits for its node to be idle, or says why it cannot.
    fn start() -> Result<Cluster, String> {
        let uid = std::os::unix::fs::MetadataExt::uid(&fs::metadata("/proc/self").unwrap());
        if uid != 0 {
            return Err("not root (slurmd must run as root to start jobs)".into());
        }
        let find = |name| find_program(name).ok_or(format!("{name} is not installed"));
        let sbin = [find("slurmctld")?, find("slurmd")?];
        for client in ["sbatch", "squeue", "scancel", "scontrol", "sinfo", "srun"] {
            find(client)?;
        }
        if Command::new("timeout").arg("--version").output().is_err() {
            return Err("coreutils timeout is missing".into());
        }
        remove_stale_clusters();

        let dir = std::env::temp_dir().join(format!("{PREFIX}{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        for sub in ["state", "spool", "work"] {
            fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let host = fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
        let host = host.trim().split('.').next().unwrap().to_owned();
        let (ctld_port, d_port) = (free_port(), free_port());
        let d = dir.display();
        let conf = dir.join("slurm.conf");
        fs::write(
            &conf,
            format!(
                "ClusterName=splashtest
SlurmctldHost={host}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/none
CredType=cred/none
SlurmctldPort={ctld_port}
SlurmdPort={d_port}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/slurmctld.log
SlurmdLogFile={d}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SlurmdParameters=config_overrides
NodeName={host} NodeAddr=127.0.0.1 CPUs={TASKS} State=UNKNOWN
PartitionName=splash Nodes={host} Default=YES MaxTime=INFINITE State=UP
"
            ),
        )
        .unwrap();
        let mut cluster = Cluster {
            dir,
            conf,
            sbin,
            daemons: Vec::new(),
        };
        let d = &cluster.dir;
        for (name, program, extra) in [
            ("slurmctld", &cluster.sbin[0], vec![]),
            ("slurmd", &cluster.sbin[1], vec!["-N", host.as_str()]),
        ] {
            let log = fs::File::create(d.join(format!("{name}.out"))).unwrap();
            let child = clean_env(&mut Command::new(program))
                .arg("-D")
                .arg("-f")
                .arg(&cluster.conf)
                .args(extra)
                .current_dir(d)
                .stdin(Stdio::null())
                .stdout(log.try_clone().unwrap())
                .stderr(log)
                .spawn()
                .map_err(|e| format!("cannot start {name}: {e}"))?;
            // Our own pid file too, for a later run to clean up after this one if it is killed.
            fs::write(d.join(format!("{name}.pid")), child.id().to_string()).unwrap();
            cluster.daemons.push((name, child));
        }
        let start = Instant::now();
        loop {
            let exited = cluster
                .daemons
                .iter_mut()
                .find_map(|(name, child)| Some((*name, child.try_wait().ok()??)));
            if let Some((name, status)) = exited {
                return Err(format!(
                    "{name} exited ({status}) at start\n{}",
                    cluster.logs()
                ));
            }
            let state = cluster
                .client("sinfo", 10)
                .args(["-h", "-N", "-o", "%T"])
                .output();
            if state.is_ok_and(|out| String::from_utf8_lossy(&out.stdout).trim() == "idle") {
                return Ok(cluster);
            }
            if start.elapsed() > Duration::from_secs(40) {
                return Err(format!(
                    "the node did not become idle in 40 s\n{}",
                    cluster.logs()
                ));
            }
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    /// A client command (`sbatch`, `squeue`, …) talking to this cluster, run in `work/`.
    fn client(&self, name: &str, seconds: u32) -> Command {
        let mut command = bounded(&find_program(name).unwrap(), seconds);
        clean_env(&mut command)
            .env("SLURM_CONF", &self.conf)
            .current_dir(self.work());
        command
    }

    fn work(&self) -> PathBuf {
        self.dir.join("work")
    }

    /// The daemons' logs and the jobs' outputs, for a failure message.
    fn logs(&self) -> String {
        let mut all = String::new();
        for daemon in ["slurmctld", "slurmd"] {
            // The log file, or what the daemon printed before it could open one.
            let log = self.dir.join(format!("{daemon}.log"));
            let log = if log.exists() {
                log
            } else {
                self.dir.join(format!("{daemon}.out"))
            };
            all += &tail(&log, 15);
        }
        for log in entries(&self.work().join("logs")) {
            all += &tail(&self.work().join("logs").join(log), 15);
        }
        all
    }

    /// Submits `script` with extra sbatch arguments; the job ID.
    fn sbatch(&self, extra: &[&str], script: &Path) -> String {
        let out = self
            .client("sbatch", 30)
            .arg("--parsable")
            .args(extra)
            .arg(script)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "sbatch: {}\n{}",
            text(&out),
            self.logs()
        );
        let id = String::from_utf8_lossy(&out.stdout).trim().to_owned();
        id.split(';').next().unwrap().to_owned()
    }

    /// Whether the job (every task of an array) has left the queue. An squeue that fails for
    /// another reason than the job being gone (a slow controller) says no, and is asked again.
    fn done(&self, job: &str) -> bool {
        let out = self
            .client("squeue", 20)
            .args(["-h", "-o", "%i", "-j", job])
            .output()
            .unwrap();
        // squeue -j of a finished job prints nothing, or says that the ID is invalid once the
        // controller has forgotten it.
        (out.status.success() && out.stdout.trim_ascii().is_empty())
            || String::from_utf8_lossy(&out.stderr).contains("Invalid job id")
    }

    fn wait(&self, job: &str, deadline: Instant) {
        while !self.done(job) {
            assert!(
                Instant::now() < deadline,
                "job {job} still queued or running after the time allowed\n{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    /// (array task ID, state, exit code) of every task of `job`, from `scontrol show job`.
    fn states(&self, job: &str) -> Vec<(u32, String, String)> {
        let out = self
            .client("scontrol", 20)
            .args(["-o", "show", "job", job])
            .output()
            .unwrap();
        assert!(out.status.success(), "scontrol: {}", text(&out));
        let mut states: Vec<_> = String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|line| {
                let field = |key: &str| {
                    line.split_whitespace()
                        .find_map(|f| f.strip_prefix(key))
                        .unwrap_or("?")
                        .to_owned()
                };
                (
                    field("ArrayTaskId=").parse().unwrap_or(u32::MAX),
                    field("JobState="),
                    field("ExitCode="),
                )
            })
            .collect();
        states.sort();
        states
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Jobs first, so that no slurmstepd or splash outlives the cluster.
        let _ = self.client("scancel", 20).args(["-u", "root"]).output();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(15) {
            let out = self.client("squeue", 10).args(["-h", "-o", "%i"]).output();
            if out.is_err() || out.is_ok_and(|o| !o.status.success() || o.stdout.is_empty()) {
                break;
            }
            std::thread::sleep(Duration::from_millis(300));
        }
        for (_, child) in &mut self.daemons {
            let _ = child.kill();
            let _ = child.wait();
        }
        // Whatever the cancel did not reach.
        kill_jobs(&self.dir);
        if std::thread::panicking() {
            eprintln!("the cluster's files are kept in {}", self.dir.display());
        } else {
            let _ = fs::remove_dir_all(&self.dir);
        }
    }
}

/// The example job script, changed only where the test must: a 3-task array with one CPU each
/// (`--shard auto/3`), this build's `splash` by its full path, and a smaller cell (r/4) so that
/// a task takes a couple of seconds per frame and can be caught between its two frames.
/// Everything else (relative `sim/`, `mesh/` and `logs/`, `--skip-existing`, the JSON logs,
/// `srun`) is the example's.
fn job_script() -> String {
    let example = fs::read_to_string(common::repository().join("examples/farm-slurm.sh")).unwrap();
    let tasks = TASKS.to_string();
    let mut script = example;
    for (from, to) in [
        (
            "#SBATCH --array=0-15",
            format!("#SBATCH --array=0-{}", TASKS - 1),
        ),
        (
            "#SBATCH --cpus-per-task=4",
            "#SBATCH --cpus-per-task=1".into(),
        ),
        (
            "--shard auto/16 --skip-existing",
            format!("--shard auto/{tasks} --skip-existing"),
        ),
        ("--cell r/2", "--cell r/4".into()),
        (
            "srun splash recon",
            format!("srun \"{}\" recon", env!("CARGO_BIN_EXE_splash")),
        ),
    ] {
        assert_eq!(
            script.matches(from).count(),
            1,
            "examples/farm-slurm.sh no longer has `{from}` once; update tests/slurm.rs"
        );
        script = script.replace(from, &to);
    }
    script
}

/// The JSON events of one task's log (`logs/splash-JOB_TASK.log`).
fn events(work: &Path, job: &str, task: u32) -> Vec<Value> {
    let log = work.join(format!("logs/splash-{job}_{task}.log"));
    fs::read_to_string(&log)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .collect()
}

fn event<'a>(events: &'a [Value], kind: &str) -> Option<&'a Value> {
    events.iter().find(|e| e["event"] == kind)
}

fn name(n: u32) -> String {
    format!("frame_{n:04}.obj")
}

#[test]
fn a_slurm_array_with_a_cancelled_task_resubmitted_makes_every_frame() {
    let begin = Instant::now();
    let cluster = match Cluster::start() {
        Ok(cluster) => cluster,
        Err(reason) => {
            eprintln!("skipped: the SLURM test cannot run here: {reason}");
            return;
        }
    };
    eprintln!(
        "slurm: one-node cluster up in {:.1} s ({})",
        begin.elapsed().as_secs_f64(),
        cluster.conf.display()
    );
    let work = cluster.work();
    // Two real frames, alternating, so that a frame written from the wrong input shows. The
    // victim's second frame (5) is the larger one, about 2 s at r/4 on one thread.
    let frames = [
        fs::read(fixture("frame_0040.ply")).unwrap(),
        fs::read(fixture("frame_0010.ply")).unwrap(),
    ];
    for n in 1..=FRAMES {
        let path = work.join(format!("sim/frame_{n:04}.ply"));
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, &frames[(n % 2 == 0) as usize]).unwrap();
    }
    fs::create_dir_all(work.join("logs")).unwrap();
    let script = work.join("farm-slurm.sh");
    fs::write(&script, job_script()).unwrap();
    let mesh = work.join("mesh");
    // Shard K = ID mod N + 1 takes positions K, K+N: the victim's frames.
    let victim_frames: Vec<u32> = (1..=FRAMES)
        .filter(|n| (n - 1) % TASKS == VICTIM % TASKS)
        .collect();
    let deadline = Instant::now() + JOB_LIMIT;

    let job = cluster.sbatch(&[], &script);
    eprintln!("slurm: submitted array job {job} (tasks 0-{})", TASKS - 1);

    // Cancel the victim once its first frame is written, while it works on the second.
    let first = mesh.join(name(victim_frames[0]));
    for tick in 0.. {
        if first.exists() {
            break;
        }
        assert!(
            Instant::now() < deadline && (tick % 25 != 0 || !cluster.done(&job)),
            "task {VICTIM} wrote no {} in time\n{}",
            first.display(),
            cluster.logs()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = cluster
        .client("scancel", 20)
        .arg(format!("{job}_{VICTIM}"))
        .output()
        .unwrap();
    assert!(out.status.success(), "scancel: {}", text(&out));
    eprintln!(
        "slurm: cancelled task {job}_{VICTIM} after it wrote {}",
        name(victim_frames[0])
    );
    cluster.wait(&job, deadline);
    let states = cluster.states(&job);
    eprintln!("slurm: array {job} ended: {states:?}");
    let lost: Vec<u32> = victim_frames
        .iter()
        .copied()
        .filter(|n| !mesh.join(name(*n)).exists())
        .collect();
    for (task, state, exit) in &states {
        if *task == VICTIM {
            assert!(
                state == "CANCELLED" || state == "COMPLETED",
                "task {task}: {state} {exit}\n{}",
                cluster.logs()
            );
            if state == "COMPLETED" {
                eprintln!("notice: task {VICTIM} finished before the cancel reached it");
            }
        } else {
            assert!(
                state == "COMPLETED" && exit == "0:0",
                "task {task}: {state} {exit}\n{}",
                cluster.logs()
            );
        }
    }
    assert_eq!(states.len(), TASKS as usize, "{states:?}");
    for task in 0..TASKS {
        let log = events(&work, &job, task);
        let written: Vec<_> = log
            .iter()
            .filter(|e| e["event"] == "frame")
            .map(|e| e["output"].as_str().unwrap_or("?").to_owned())
            .collect();
        let summary = event(&log, "summary").map_or("no summary: killed".into(), |e| e.to_string());
        eprintln!("slurm: task {job}_{task} wrote {written:?}; {summary}");
    }
    let left = entries(&mesh);
    eprintln!("slurm: after the cancel, mesh/ has {left:?}; missing frames {lost:?}");

    // The documented resubmission: the killed task alone, by its ID.
    let array = format!("--array={VICTIM}");
    let again = cluster.sbatch(&[&array], &script);
    eprintln!("slurm: resubmitted `sbatch {array} farm-slurm.sh` as job {again}");
    cluster.wait(&again, deadline);
    let states = cluster.states(&again);
    eprintln!("slurm: job {again} ended: {states:?}");
    assert_eq!(
        states,
        vec![(VICTIM, "COMPLETED".to_owned(), "0:0".to_owned())],
        "{}",
        cluster.logs()
    );
    let log = events(&work, &again, VICTIM);
    let (start, summary) = (event(&log, "start"), event(&log, "summary"));
    eprintln!(
        "slurm: resubmitted task's log: {}\n       {}",
        start.map_or("no start event".into(), |e| e.to_string()),
        summary.map_or("no summary event".into(), |e| e.to_string()),
    );
    let (start, summary) = (start.unwrap(), summary.unwrap());
    // Same shard as in the array, whatever SLURM_ARRAY_TASK_MIN the resubmission has.
    assert_eq!(start["shard"], format!("{}/{TASKS}", VICTIM % TASKS + 1));
    assert_eq!(summary["written"], lost.len());
    assert_eq!(summary["skipped"], victim_frames.len() - lost.len());
    assert_eq!(summary["ok"], true);

    // Every frame, nothing else (no temporary of the killed task), equal to a plain run's.
    let expected: Vec<String> = (1..=FRAMES).map(name).collect();
    assert_eq!(entries(&mesh), expected, "{}", cluster.logs());
    let plain = work.join("plain");
    let out = clean_env(&mut Command::new(env!("CARGO_BIN_EXE_splash")))
        .current_dir(&work)
        .args(["recon", "sim/", "--spacing", "0.014", "--cell", "r/4", "-q"])
        .arg("-o")
        .arg("plain/")
        .output()
        .unwrap();
    assert!(out.status.success(), "plain run: {}", text(&out));
    for file in &expected {
        let (farm, alone) = (
            fs::read(mesh.join(file)).unwrap(),
            fs::read(plain.join(file)).unwrap(),
        );
        assert!(
            farm == alone,
            "{file}: the farm's mesh differs from the plain run's"
        );
    }
    eprintln!(
        "slurm: all {FRAMES} frames equal the plain run's byte for byte; {:.1} s in all",
        begin.elapsed().as_secs_f64()
    );
}
