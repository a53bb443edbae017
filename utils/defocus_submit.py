#!/usr/bin/python3
"""defocus-submit -- render a defocus sequence on a render farm, in chunks

Usage:
  defocus-submit --chunk-size N [farm options] INPUT... -o OUTPUT.#.exr [defocus options]
   or: defocus-submit --chunk-size N [farm options] SHOT.dof -o OUTPUT.#.exr [defocus options]
   or: defocus-submit --resume [farm options] (the same arguments)
   or: defocus-submit --check --job-dir DIR

The shot (inputs and defocus options) is saved as DIR/shot.dof and its
frames are cut into chunks of at most N neighbouring frames. One array job
renders them, a task per chunk, each task running

  defocus DIR/shot.dof -o OUTPUT --chunk K/CHUNKS --skip-existing

so any scheduler that runs a command per task can run the same chunks. A
final job, started once every task has ended, checks every frame and prints
"N of M frames written; failed: ..." (DIR/check.log). --resume submits only
the chunks with frames missing or written with other settings; each frame
records a hash of its settings (defocus:settingsHash), so a task renders
only what is missing.

Memory per task is the first frame's measured peak times the frames a task
runs at once (--cpus), unless --mem gives it. --dry-run prints what would
be written and submitted, and writes, renders and submits nothing. A
resubmitted chunk logs to chunk_K.attemptA.log, keeping its earlier logs;
a new submission into a job folder moves the earlier one's files to
DIR/earlier.N. The output pattern and --mem are checked as each task's
defocus checks them, so a job that every task would refuse is not
submitted.
"""
import argparse
import importlib.util
import json
import math
import os
import re
import resource
import shlex
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
# Where this script finds the Python package: beside it in the build tree,
# in <prefix>/lib/python3/dist-packages once installed (set by CMake).
sys.path.insert(0, os.path.normpath(os.path.join(HERE, "@DEFOCUS_SUBMIT_PYTHONPATH@")))


def imported_on_first_use(name):
    """The module, run only when one of its names is first read: importing
    defocus loads OpenImageIO's libraries (half a second), which --help
    and a call refused for its own arguments need not wait for."""
    spec = importlib.util.find_spec(name)
    spec.loader = importlib.util.LazyLoader(spec.loader)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


defocus = imported_on_first_use("defocus")

DEFOCUS = os.path.join(HERE, "defocus")


def fail(message):
    sys.exit(f"defocus-submit: {message}")


def sbatch_value(value):
    """A value as an #SBATCH line must hold it for Slurm to read it as
    given: quoted when it has more than plain characters (Slurm reads
    quotes and backslashes there, and an unquoted '#' starts a comment)."""
    if re.fullmatch(r"[A-Za-z0-9._/:@+=,%-]+", value):
        return value
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'


def slurm_pattern(text):
    """Text as itself in a Slurm file name pattern, where '%' is special."""
    return text.replace("%", "%%")


class Slurm:
    """Slurm through sbatch. A scheduler here is what submits an array job
    (one task per chunk, the task's chunk number in an environment
    variable) and a job that runs after it: OpenCue (a layer of frames
    1-CHUNKS, chunk size 1, #IFRAME# as K), Deadline (a job of frames
    1-CHUNKS, <STARTFRAME> as K) or Tractor (a task per chunk) take the same
    two commands. Every value reaches the scripts quoted: for Slurm on the
    #SBATCH lines (sbatch_value), for the shell in the commands
    (shlex.quote), and none holds a control character (main refuses them)."""

    name = "slurm"
    task_variable = "$SLURM_ARRAY_TASK_ID"

    def options(self, job):
        lines = [f"#SBATCH --partition={sbatch_value(job['partition'])}"] if job["partition"] else []
        return lines + ([f"#SBATCH --time={sbatch_value(job['time'])}"] if job["time"] else [])

    def array_script(self, job, tasks, command):
        lines = ["#!/bin/bash",
                 f"#SBATCH --job-name={job['name']}",
                 f"#SBATCH --array={tasks}",
                 f"#SBATCH --cpus-per-task={job['cpus']}",
                 f"#SBATCH --mem={job['mem_mb']}M",
                 f"#SBATCH --output={sbatch_value(slurm_pattern(job['dir']) + '/chunk_%a' + job['log_suffix'] + '.log')}"]
        return "\n".join(lines + self.options(job) + ["set -eu", "exec " + command]) + "\n"

    def after_script(self, job, after_id, command):
        lines = ["#!/bin/bash",
                 f"#SBATCH --job-name={job['name']}-check",
                 f"#SBATCH --dependency=afterany:{after_id}",
                 "#SBATCH --cpus-per-task=1",
                 "#SBATCH --mem=256M",
                 f"#SBATCH --output={sbatch_value(slurm_pattern(job['dir']) + '/check.log')}"]
        return "\n".join(lines + self.options(job) + ["exec " + command]) + "\n"

    def submit(self, script):
        run = subprocess.run(["sbatch", "--parsable"], input=script, text=True,
                             capture_output=True)
        if run.returncode != 0:
            fail(f"sbatch: {run.stderr.strip() or 'failed'}")
        return run.stdout.strip().split(";")[0]


SCHEDULERS = {"slurm": Slurm}


def parse_size_mb(text):
    """A size such as 4G, 800M or 1.5T in MB (a bare number is MB, as Slurm
    reads it): a positive decimal number, at most an exabyte."""
    units = {"": 1, "K": 1 / 1024, "M": 1, "G": 1024, "T": 1024 * 1024}
    size = re.fullmatch(r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)([KMGT]?)B?", text.strip(), re.IGNORECASE)
    mb = float(size[1]) * units[size[2].upper()] if size else 0
    if not 0 < mb <= 2 ** 40:
        fail(f"--mem: '{text}' is not a size (e.g. 4G, 800M)")
    return max(1, math.ceil(mb))


def first_frame_peak_mb(shot_file, frame, cpus):
    """Renders `frame` here and returns the process's peak memory in MB (the
    largest of this script's children, which this render is)."""
    with tempfile.TemporaryDirectory() as scratch:
        run = subprocess.run([DEFOCUS, shot_file, "-o", os.path.join(scratch, "probe.exr"),
                              "--frames", str(frame), "--threads", str(cpus), "-q"],
                             capture_output=True, text=True)
        if run.returncode != 0:
            fail(f"measuring frame {frame}: {run.stderr.strip()}")
        return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024


def chunk_status(job, shot):
    """Per chunk, the frames not written with the shot's settings."""
    missing = {}
    for k in range(1, job["chunks"] + 1):
        for frame in defocus.chunk_frames(job["frames"], k, job["chunks"]):
            path = defocus.frame_path(job["output"], frame)
            current, why = defocus.written_with_settings(path, shot.settings_hash(frame))
            if not current:
                missing.setdefault(k, []).append((frame, why))
    return missing


def ranges(frames):
    """1,2,3,5 -> '1-3,5'."""
    out, start = [], None
    for i, f in enumerate(frames):
        if start is None:
            start = f
        if i + 1 == len(frames) or frames[i + 1] != f + 1:
            out.append(str(start) if start == f else f"{start}-{f}")
            start = None
    return ",".join(out)


def log_path(job, k):
    """The log of chunk K's latest task."""
    return job.get("logs", {}).get(str(k), os.path.join(job["dir"], f"chunk_{k}.log"))


def check(job_dir):
    """The final job: every frame there, whole, written with the shot's
    settings."""
    with open(os.path.join(job_dir, "job.json")) as f:
        job = json.load(f)
    shot = defocus.Shot.load(os.path.join(job_dir, "shot.dof"))
    missing = chunk_status(job, shot)
    failed = sorted(frame for frames in missing.values() for frame, _ in frames)
    total = len(job["frames"])
    summary = f"{total - len(failed)} of {total} frames written"
    if not failed:
        print(f"defocus-submit: {summary}")
        return 0
    chunks = ", ".join(f"chunk {k} (log {log_path(job, k)}): frames "
                       f"{ranges([f for f, _ in v])}" for k, v in sorted(missing.items()))
    print(f"defocus-submit: {summary}; failed: {ranges(failed)} -- {chunks}; "
          f"resubmit them with defocus-submit --resume and the same arguments")
    for frame, why in sorted(f for frames in missing.values() for f in frames)[:10]:
        print(f"  frame {frame}: {defocus.frame_path(job['output'], frame)} {why}")
    return 1


def refuse_control_characters(arguments):
    """A newline in a value would start a line of its own in a batch script,
    which the scheduler runs: no argument may hold a control character."""
    for argument in arguments:
        if any(ord(c) < 32 or ord(c) == 127 for c in argument):
            fail(f"{argument!r}: an argument holds a control character")


def job_name(given, output):
    """The job's name, which also names its folder: letters, digits, '.',
    '_' and '-', and not '.' or '..'."""
    if given is not None:
        if not re.fullmatch(r"[A-Za-z0-9._-]+", given) or set(given) == {"."}:
            fail(f"--job-name: '{given}' is not a name of letters, digits, '.', '_' and '-' "
                 "(it names the job's folder)")
        return given
    stem = os.path.basename(output).split(".")[0].strip("#@%")
    return re.sub(r"[^A-Za-z0-9._-]", "_", stem).lstrip(".") or "defocus"


class VersionAction(argparse.Action):
    """--version, which alone of the options needs the module to answer."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0,
                         help="show program's version number and exit", **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"defocus-submit {defocus.__version__}")
        parser.exit()


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """argparse's help with "Usage:" spelt as help2man and the other tools
    spell it, so that the man page's synopsis holds every form."""

    def add_usage(self, usage, actions, groups, prefix=None):
        super().add_usage(usage, actions, groups, prefix or "Usage: ")


def main():
    parser = argparse.ArgumentParser(
        prog="defocus-submit", formatter_class=HelpFormatter,
        description=__doc__.split("\n", 2)[2].split("\n\n", 1)[1],
        usage=__doc__.split("Usage:\n", 1)[1].split("\n\n")[0].strip(),
        epilog="Example:\n  defocus-submit --chunk-size 10 --cpus 4 plate.#.exr --frames 1001-1240 "
               "\\\n      --focal 35 --fstop 2 --focus 1001:3,1240:1.2 -o /shows/x/dof/dof.#.exr")
    farm = parser.add_argument_group("farm options")
    farm.add_argument("--chunk-size", type=int, metavar="N", help="frames per task")
    farm.add_argument("--scheduler", default="slurm", choices=sorted(SCHEDULERS))
    farm.add_argument("--cpus", type=int, default=2, metavar="N",
                      help="CPUs per task, the frames it renders at once (default: 2)")
    farm.add_argument("--mem", metavar="SIZE",
                      help="memory per task, e.g. 8G (a bare number is MB, as Slurm reads it; "
                           "default: measured from the first frame)")
    farm.add_argument("--partition", help="the partition (queue) to run in")
    farm.add_argument("--time", help="time limit per task, e.g. 2:00:00")
    farm.add_argument("--job-name", help="(default: the output's name)")
    farm.add_argument("--job-dir", metavar="DIR",
                      help="the shot, logs and job description "
                           "(default: OUTPUT's folder/defocus-farm/JOB_NAME)")
    farm.add_argument("--dry-run", action="store_true",
                      help="print what would be written and submitted, the batch scripts "
                           "included; write, render and submit nothing")
    farm.add_argument("--resume", action="store_true",
                      help="submit only the chunks with frames missing or written with "
                           "other settings")
    farm.add_argument("--check", action="store_true",
                      help="check a submitted job's frames (what its final job runs)")
    farm.add_argument("-o", dest="output", metavar="OUTPUT", help="output frame pattern")
    farm.add_argument("--version", action=VersionAction)
    refuse_control_characters(sys.argv[1:])
    args, shot_args = parser.parse_known_args()

    if args.check:
        if not args.job_dir:
            fail("--check needs --job-dir DIR")
        return check(args.job_dir)
    if not args.output:
        fail("no output: give -o OUTPUT.#.exr")
    if not args.chunk_size or args.chunk_size < 1:
        fail("give --chunk-size N, the frames of one task (N >= 1)")
    if args.cpus < 1:
        fail("--cpus: at least 1")
    if not shot_args:
        fail("no input: give the inputs or a .dof and the defocus options")
    mem_mb = parse_size_mb(args.mem) if args.mem else None
    output = os.path.abspath(args.output)
    if not os.path.isdir(os.path.dirname(output)):
        fail(f"{args.output}: the folder {os.path.dirname(output)} does not exist")
    name = job_name(args.job_name, output)
    job_dir = os.path.abspath(args.job_dir or os.path.join(os.path.dirname(output),
                                                           "defocus-farm", name))
    earlier_shot = os.path.join(job_dir, "shot.dof")
    earlier = defocus.Shot.load(earlier_shot) if args.resume and os.path.exists(earlier_shot) \
        else None
    with tempfile.TemporaryDirectory() as scratch:
        # defocus reads the options into the shot, aside until the job is
        # checked as its tasks would check it.
        shot_file = os.path.join(scratch, "shot.dof")
        run = subprocess.run([DEFOCUS, *shot_args, "--save-scene", shot_file, "-q"],
                             capture_output=True, text=True)
        if run.returncode != 0:
            fail(run.stderr.strip().removeprefix("defocus: "))
        # The frames, every one of whose inputs is there (the shot's
        # missing-frames setting decides what a gap does).
        shot = defocus.Shot.load(shot_file)
        frames = shot.frames_to_render()
        refuse_what_tasks_would_refuse(shot, frames, output, mem_mb)
        if earlier and earlier.settings_hash(frames[0]) != shot.settings_hash(frames[0]):
            print("defocus-submit: --resume: the settings differ from the earlier "
                  "submission's: every frame written with those is rendered again")
        if not args.dry_run:
            os.makedirs(job_dir, exist_ok=True)
            if not args.resume:
                keep_earlier_submission(job_dir)
            # Saved again, its paths relative to the job's folder where beneath it.
            try:
                shot.save(earlier_shot)
            except defocus.Error as e:
                fail(str(e))
        return submit(args, shot, earlier_shot, shot_file, name, job_dir, output, mem_mb)


def refuse_what_tasks_would_refuse(shot, frames, output, mem_mb):
    """The checks each task's defocus makes before it renders, made once
    here: a job that every task would refuse is not submitted."""
    if len(frames) > 1 and defocus.frame_path(output, frames[0]) == output:
        fail(f"-o {output}: {len(frames)} frames need a frame pattern in the name, "
             "e.g. out.#.exr")
    if mem_mb:
        limited = defocus._defocus.NativeShot(shot._native)
        limited.set("memory-limit", f"{mem_mb}M", "--mem")
        try:
            limited.fits(frames[0])
        except defocus.Error as e:
            fail(f"--mem {mem_mb}M: {e}")


def keep_earlier_submission(job_dir):
    """Moves an earlier submission's files in `job_dir` (its job, shot and
    logs) to a folder of their own, earlier.N, so a new one overwrites
    none."""
    files = [f for f in os.listdir(job_dir)
             if f in ("job.json", "shot.dof", "check.log", "submitted.log")
             or re.fullmatch(r"chunk_\d+(\.attempt\d+)?\.log", f)]
    if not files:
        return
    n = 1
    while os.path.exists(os.path.join(job_dir, f"earlier.{n}")):
        n += 1
    kept = os.path.join(job_dir, f"earlier.{n}")
    os.mkdir(kept)
    for f in files:
        os.rename(os.path.join(job_dir, f), os.path.join(kept, f))
    print(f"defocus-submit: the earlier submission's files are kept in {kept}")


def submit(args, shot, shot_file, read_from, name, job_dir, output, mem_mb):
    frames = shot.frames_to_render()
    chunks = math.ceil(len(frames) / args.chunk_size)
    scheduler = SCHEDULERS[args.scheduler]()
    job_file = os.path.join(job_dir, "job.json")
    earlier = {}
    if args.resume and os.path.exists(job_file):
        with open(job_file) as f:
            earlier = json.load(f)
    attempt = earlier.get("attempt", 1) + 1 if args.resume else 1
    job = {"name": name, "dir": job_dir, "output": output, "frames": frames, "chunks": chunks,
           "cpus": args.cpus, "partition": args.partition, "time": args.time,
           "scheduler": scheduler.name, "attempt": attempt,
           "log_suffix": f".attempt{attempt}" if attempt > 1 else "",
           "logs": dict(earlier.get("logs", {}))}

    tasks = list(range(1, chunks + 1))
    if args.resume:
        tasks = sorted(chunk_status(job, shot))
        if not tasks:
            print(f"defocus-submit: nothing to resume: all {len(frames)} frames are written")
            return 0
    # Each task's log is new: a resubmitted chunk keeps the logs of its
    # earlier attempts.
    for k in tasks:
        job["logs"][str(k)] = os.path.join(job_dir, f"chunk_{k}{job['log_suffix']}.log")
    first = defocus.chunk_frames(frames, tasks[0], chunks)[0]
    if mem_mb:
        job["mem_mb"] = mem_mb
    elif args.dry_run:
        job["mem_mb"] = f"<measured from frame {first}>"
    else:
        # Frames in flight each take about one frame's peak; a margin for the
        # process and the scheduler's own accounting.
        peak = first_frame_peak_mb(read_from, first, args.cpus)
        job["mem_mb"] = math.ceil(peak * min(args.cpus, args.chunk_size) * 1.25 + 256)

    task_command = " ".join([
        shlex.quote(DEFOCUS), shlex.quote(shot_file), "-o", shlex.quote(output),
        "--chunk", f'"{scheduler.task_variable}/{chunks}"', "--skip-existing",
        "--threads", str(args.cpus), "--memory-limit", shlex.quote(f"{job['mem_mb']}M"), "-v"])
    check_command = " ".join([shlex.quote(os.path.join(HERE, "defocus-submit")), "--check",
                              "--job-dir", shlex.quote(job_dir)])
    array = scheduler.array_script(job, ",".join(map(str, tasks)), task_command)
    if args.dry_run:
        print(f"defocus-submit: dry run: would write {shot_file} and {job_file}, and submit "
              f"{len(tasks)} of {chunks} chunk(s) of at most {args.chunk_size} frames "
              f"({len(frames)} frames):")
        print(array)
        print(scheduler.after_script(job, "<array job id>", check_command))
        return 0
    defocus._defocus.write_text_atomic(job_file, json.dumps(job, indent=2) + "\n")
    array_id = scheduler.submit(array)
    check_id = scheduler.submit(scheduler.after_script(job, array_id, check_command))
    with open(os.path.join(job_dir, "submitted.log"), "a") as f:
        f.write(f"{array_id} {check_id} chunks {','.join(map(str, tasks))}\n")
    print(f"defocus-submit: {name}: {len(tasks)} of {chunks} chunk(s) of at most "
          f"{args.chunk_size} frames ({len(frames)} frames), {args.cpus} CPUs and "
          f"{job['mem_mb']} MB a task: array job {array_id}, check job {check_id}; "
          f"logs in {job_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
