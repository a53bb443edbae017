#!/usr/bin/python3
"""defocus-submit on a real one-node Slurm cluster, started by this test.

munged, slurmctld and slurmd run in the foreground as this test's own
processes, with a slurm.conf for this host in a temporary folder, and are
stopped by their PIDs at the end. Then:
 1. a 24-frame focus pull is submitted in 4 chunks; its frames must be
    bit-identical to a single-machine defocus run, and the final job must
    report all of them written;
 2. it is submitted again, one chunk's task is cancelled (scancel) after its
    first frame, and the final job must report that chunk's missing frames;
    --resume must submit only that chunk, render only the missing frames
    (its new log, chunk_3.attempt2.log, and the files' mtimes say so), keep
    every earlier log as it was, and leave every frame identical to the
    single-machine run again.
When Slurm cannot start here, the test prints why and exits 77 (skipped).

    slurm_test.py BIN_DIR SCRATCH_DIR    (PYTHONPATH: the defocus package)
"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

import OpenImageIO as oiio

bin_dir, scratch = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
DEFOCUS = os.path.join(bin_dir, "defocus")
SUBMIT = os.path.join(bin_dir, "defocus-submit")
daemons = []


def skip(why):
    print(f"SKIPPED: Slurm cannot run here: {why}")
    stop_daemons()
    sys.exit(77)


def fail(why):
    print(f"FAILED: {why}")
    for log in ("slurmctld.log", "slurmd.log"):
        path = os.path.join(scratch, "slurm", log)
        if os.path.exists(path):
            print(f"--- {log} (last lines)")
            print("".join(open(path).readlines()[-15:]))
    stop_daemons()
    sys.exit(1)


def stop_daemons():
    for process in reversed(daemons):
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
    for process in reversed(daemons):
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
    daemons.clear()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run(*args, check=True, **kwargs):
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    if check and result.returncode != 0:
        fail(f"{' '.join(map(str, args))}: {result.stderr.strip() or result.stdout.strip()}")
    return result


def start_cluster():
    conf_dir = os.path.join(scratch, "slurm")
    for folder in ("state", "spool"):
        os.makedirs(os.path.join(conf_dir, folder), exist_ok=True)
    for tool in ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel", "sinfo"):
        if not shutil.which(tool) and not os.path.exists(f"/usr/sbin/{tool}"):
            skip(f"{tool} is not installed (Debian: slurm-wlm, munge)")
    key = "/etc/munge/munge.key"
    if not os.path.exists(key):
        skip(f"no munge key at {key}")
    sock = os.path.join(conf_dir, "munge.socket")
    daemons.append(subprocess.Popen(
        ["/usr/sbin/munged", "--foreground", "--force", f"--key-file={key}", f"--socket={sock}",
         f"--pid-file={conf_dir}/munged.pid", f"--seed-file={conf_dir}/munge.seed",
         f"--log-file={conf_dir}/munged.log"],
        stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT))
    host = socket.gethostname().split(".")[0]
    memory_mb = int(int(open("/proc/meminfo").readline().split()[1]) / 1024 * 0.8)
    conf = os.path.join(conf_dir, "slurm.conf")
    with open(conf, "w") as f:
        f.write(f"""ClusterName=defocustest
SlurmctldHost={host}(127.0.0.1)
AuthType=auth/munge
AuthInfo=socket={sock}
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
StateSaveLocation={conf_dir}/state
SlurmdSpoolDir={conf_dir}/spool
SlurmctldPidFile={conf_dir}/slurmctld.pid
SlurmdPidFile={conf_dir}/slurmd.pid
SlurmctldLogFile={conf_dir}/slurmctld.log
SlurmdLogFile={conf_dir}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
KillWait=5
NodeName={host} NodeAddr=127.0.0.1 CPUs={os.cpu_count()} RealMemory={memory_mb} State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
""")
    os.environ["SLURM_CONF"] = conf
    for _ in range(50):
        if os.path.exists(sock):
            break
        time.sleep(0.1)
    else:
        skip("munged did not start")
    daemons.append(subprocess.Popen(["/usr/sbin/slurmctld", "-D", "-f", conf],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT))
    time.sleep(1)
    daemons.append(subprocess.Popen(["/usr/sbin/slurmd", "-D", "-f", conf],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        for process in daemons:
            if process.poll() is not None:
                skip(f"{process.args[0]} exited with {process.returncode}; see {conf_dir}")
        state = run("sinfo", "-h", "-o", "%T", check=False).stdout.strip()
        if state == "idle":
            return
        time.sleep(0.5)
    skip(f"the node did not come up (sinfo says '{state}'); see {conf_dir}")


def wait_for(job_ids, timeout=600):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        queued = run("squeue", "-h", "-j", ",".join(job_ids), check=False).stdout.strip()
        if not queued:
            return
        time.sleep(1)
    fail(f"jobs {job_ids} still queued after {timeout} s")


def submit(*args):
    result = run(SUBMIT, *args)
    ids = re.search(r"array job (\d+), check job (\d+)", result.stdout)
    if not ids:
        fail(f"defocus-submit said: {result.stdout}")
    return result.stdout, [ids.group(1), ids.group(2)]


def pixels(path):
    """A file's pixels, in its own pixel type."""
    inp = oiio.ImageInput.open(path)
    if not inp:
        fail(f"{path}: {oiio.geterror()}")
    data = inp.read_image(oiio.UNKNOWN)
    inp.close()
    return data


def same_frames(folder, reference, frames):
    for f in frames:
        ours, theirs = os.path.join(folder, f"f.{f:04d}.exr"), os.path.join(reference, f"f.{f:04d}.exr")
        if not os.path.exists(ours):
            fail(f"frame {f} missing from {folder}")
        if pixels(ours).tobytes() != pixels(theirs).tobytes():
            fail(f"frame {f} of {folder} differs from the single-machine render")


def main():
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    start_cluster()
    scene = os.path.join(scratch, "scene.exr")
    run(os.path.join(bin_dir, "make_example_scene"), scene, "--width", "640", "--height", "360")
    shot = [scene, "--frames", "1-24", "--focal", "50", "--fstop", "1.8",
            "--focus", "1:4,24:1.5", "--cateye", "1"]
    frames = list(range(1, 25))
    single = os.path.join(scratch, "single")
    os.makedirs(single)
    run(DEFOCUS, *shot, "-o", os.path.join(single, "f.#.exr"), "-q")

    # 1. Four chunks of six frames, memory measured from the first frame.
    farm = os.path.join(scratch, "farm")
    os.makedirs(farm)
    out, ids = submit("--chunk-size", "6", "--cpus", "1", "--job-dir",
                      os.path.join(scratch, "job1"), *shot, "-o", os.path.join(farm, "f.#.exr"))
    if "4 of 4 chunk(s)" not in out:
        fail(f"expected 4 chunks: {out}")
    wait_for(ids)
    check_log = open(os.path.join(scratch, "job1", "check.log")).read()
    if "24 of 24 frames written" not in check_log:
        fail(f"the final job said: {check_log}")
    same_frames(farm, single, frames)
    print("24 frames in 4 chunks: bit-identical to one machine")

    # 2. A chunk cancelled mid-run, then resumed.
    farm2, job2 = os.path.join(scratch, "farm2"), os.path.join(scratch, "job2")
    os.makedirs(farm2)
    args = ["--chunk-size", "6", "--cpus", "1", "--mem", "1G", "--job-dir", job2, *shot,
            "-o", os.path.join(farm2, "f.#.exr")]
    out, ids = submit(*args)
    chunk3 = frames[12:18]
    deadline = time.monotonic() + 300
    while not any(os.path.exists(os.path.join(farm2, f"f.{f:04d}.exr")) for f in chunk3):
        if time.monotonic() > deadline:
            fail("chunk 3 wrote no frame in 300 s")
        time.sleep(0.05)
    run("scancel", f"{ids[0]}_3")
    wait_for(ids)
    written = {f: os.stat(os.path.join(farm2, f"f.{f:04d}.exr")).st_mtime_ns
               for f in frames if os.path.exists(os.path.join(farm2, f"f.{f:04d}.exr"))}
    missing = [f for f in frames if f not in written]
    if not missing or not set(missing) <= set(chunk3):
        fail(f"after cancelling chunk 3, missing frames {missing}; expected some of {chunk3}")
    check_log = open(os.path.join(job2, "check.log")).read()
    if f"{24 - len(missing)} of 24 frames written; failed: " not in check_log \
            or "chunk 3" not in check_log:
        fail(f"the final job did not report chunk 3's frames: {check_log}")
    logs = {k: open(os.path.join(job2, f"chunk_{k}.log")).read() for k in (1, 2, 3, 4)}
    out, ids = submit("--resume", *args)
    if "1 of 4 chunk(s)" not in out:
        fail(f"--resume should submit chunk 3 alone: {out}")
    wait_for(ids)
    if "24 of 24 frames written" not in open(os.path.join(job2, "check.log")).read():
        fail("the final job after --resume did not find all 24 frames")
    for f, mtime in written.items():
        if os.stat(os.path.join(farm2, f"f.{f:04d}.exr")).st_mtime_ns != mtime:
            fail(f"frame {f} was written before the cancel and rendered again")
    # The resubmitted chunk logs anew; the cancelled attempt's log is kept.
    log3 = open(os.path.join(job2, "chunk_3.attempt2.log")).read()
    rendered = sorted(int(m) for m in re.findall(r"frame (\d+)(?: \(\d+/\d+\))?: wrote", log3))
    skipped = sorted(int(m) for m in re.findall(r"frame (\d+): skipped", log3))
    if rendered != missing or skipped != [f for f in chunk3 if f not in missing]:
        fail(f"the resumed chunk rendered {rendered} and skipped {skipped}; "
             f"missing were {missing}\n{log3}")
    for k, log in logs.items():
        if open(os.path.join(job2, f"chunk_{k}.log")).read() != log:
            fail(f"chunk {k}'s log changed on --resume")
    same_frames(farm2, single, frames)
    print(f"chunk 3 cancelled with frames {missing} missing; --resume rendered only those: "
          "all 24 bit-identical to one machine")
    stop_daemons()
    print("slurm test passed")


if __name__ == "__main__":
    try:
        main()
    finally:
        stop_daemons()
