"""defocus-submit against hostile values and careless use: no value can add a
command to a batch script, a dry run writes and runs nothing, a resubmitted
chunk keeps its earlier logs, a sequence with a gap is refused.

sbatch is replaced by a stub on PATH that keeps the scripts it is given, and
the scripts are run with their final `exec` printing its arguments instead.
"""
import json
import os
import stat
import subprocess

import pytest

DEFOCUS_BIN = os.environ["DEFOCUS_BIN"]
SUBMIT = os.path.join(os.path.dirname(DEFOCUS_BIN), "defocus-submit")

# Printable, and each one a command or a pattern if quoted wrongly.
HOSTILE = ["a b", "x%j%a", 'q"uote', "it's", "$(touch PWNED)", "`touch PWNED`", "a;touch PWNED",
           "#not a comment", "back\\slash", "*"]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("submit_scene") / "plate.0001.exr"
    subprocess.run([os.environ["MAKE_EXAMPLE_SCENE_BIN"], str(path), "--width", "48",
                    "--height", "27"], check=True, capture_output=True)
    return path


@pytest.fixture
def stub_sbatch(tmp_path, monkeypatch):
    """A folder where the stub sbatch leaves each script it is given."""
    folder = tmp_path / "sbatch"
    folder.mkdir()
    stub = folder / "sbatch"
    stub.write_text('#!/bin/sh\nn=$(ls "$(dirname "$0")" | wc -l)\n'
                    'cat > "$(dirname "$0")/script.$n"\necho "$((1000 + n))"\n')
    stub.chmod(stub.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setenv("PATH", f"{folder}:{os.environ['PATH']}")
    return folder


def submit(*args):
    return subprocess.run([SUBMIT, *map(str, args)], capture_output=True, text=True)


def slurm_arguments(line):
    """The arguments sbatch reads from an #SBATCH line: quotes group
    characters, a backslash takes the next one as it is, an unquoted '#'
    ends the line (Slurm's _get_argument)."""
    arguments, current, quote, escaped, started = [], "", None, False, False
    for c in line[len("#SBATCH"):]:
        if escaped:
            current, escaped, started = current + c, False, True
        elif c == "\\":
            escaped = True
        elif quote:
            if c == quote:
                quote = None
            else:
                current += c
        elif c in "\"'":
            quote, started = c, True
        elif c == "#":
            break
        elif c.isspace():
            if started:
                arguments.append(current)
            current, started = "", False
        else:
            current, started = current + c, True
    return arguments + ([current] if started else [])


def sbatch_options(script):
    options = {}
    for line in script.splitlines():
        if line.startswith("#SBATCH"):
            for argument in slurm_arguments(line):
                name, _, value = argument.partition("=")
                options[name] = value
    return options


def run_script(script, folder):
    """Runs a batch script in `folder` with its final exec printing the
    command's arguments, one a line, instead of running it."""
    lines = script.splitlines()
    assert lines[-1].startswith("exec ")
    body = "\n".join(lines[:-1] + ["printf '%s\\n' " + lines[-1][len("exec "):]])
    run = subprocess.run(["bash", "-c", body], cwd=folder, capture_output=True, text=True,
                         env={**os.environ, "SLURM_ARRAY_TASK_ID": "1"})
    assert run.returncode == 0, run.stderr
    return run.stdout.splitlines()


def test_control_characters_in_any_value_are_refused(scene, tmp_path, stub_sbatch):
    out = tmp_path / "out.#.exr"
    base = ["--chunk-size", "1", "--mem", "1G", "--focus", "3"]
    # Every argument goes through one check, so each option is tried with
    # one of the characters in turn, and each character with some option.
    bad_values = ["x\ntouch PWNED", "x\rtouch PWNED", "x\x1b[2J", "x\x7f"]
    options = ["-o", "--job-name", "--time", "--partition", "--job-dir", "input"]
    for i, option in enumerate(options):
        bad = bad_values[i % len(bad_values)]
        args = [*base, scene, "-o", out]
        if option == "input":
            args[args.index(scene)] = str(scene) + bad
        elif option == "-o":
            args[-1] = str(out) + bad
        else:
            args += [option, bad]
        run = submit(*args)
        assert run.returncode != 0, (option, bad)
        assert run.stderr.count("\n") == 1 and "holds a control character" in run.stderr
    assert os.listdir(stub_sbatch) == ["sbatch"]  # nothing submitted
    assert not (tmp_path / "defocus-farm").exists()


def test_job_names_are_plain_names_that_stay_in_the_job_folder(scene, tmp_path):
    for bad in ["../../x", "a/b", "..", ".", "x y", "x%j", ""]:
        run = submit("--dry-run", "--chunk-size", "1", "--mem", "1G", "--job-name", bad, scene,
                     "--focus", "3", "-o", tmp_path / "out.#.exr")
        assert run.returncode != 0, bad
        assert "--job-name" in run.stderr and run.stderr.count("\n") == 1
    # The default is made plain from the output's name.
    odd = tmp_path / "my shot;x"
    odd.mkdir()
    run = submit("--dry-run", "--chunk-size", "1", "--mem", "1G", scene, "--focus", "3",
                 "-o", odd / "$(x) dof.#.exr")
    assert run.returncode == 0, run.stderr
    assert "#SBATCH --job-name=__x__dof\n" in run.stdout


@pytest.mark.parametrize("value", HOSTILE)
def test_hostile_values_reach_slurm_and_the_shell_as_given(scene, tmp_path, stub_sbatch, value):
    folder = tmp_path / f"out {value}"
    folder.mkdir()
    out = folder / f"o{value}.#.exr"
    job_dir = tmp_path / f"job {value}"
    run = submit("--chunk-size", "1", "--cpus", "1", "--mem", "1G", "--time", f"1:00 {value}",
                 "--partition", f"p{value}", "--job-dir", job_dir, scene, "--focus", "3",
                 "-o", out)
    assert run.returncode == 0, run.stderr
    array, after = (stub_sbatch / "script.1").read_text(), (stub_sbatch / "script.2").read_text()
    for script in (array, after):
        # Only the lines the script is made of: none came from a value.
        for line in script.splitlines():
            assert line in ("#!/bin/bash", "set -eu") or line.startswith(("#SBATCH --", "exec "))
        assert subprocess.run(["bash", "-n", "-c", script]).returncode == 0
        options = sbatch_options(script)
        assert options["--time"] == f"1:00 {value}"
        assert options["--partition"] == f"p{value}"
    # Slurm fills in %a (the task) and nothing else of the log's name.
    assert sbatch_options(array)["--output"] == \
        str(job_dir).replace("%", "%%") + "/chunk_%a.log"
    assert sbatch_options(after)["--output"] == str(job_dir).replace("%", "%%") + "/check.log"
    argv = run_script(array, tmp_path)
    assert argv[:5] == [DEFOCUS_BIN, str(job_dir / "shot.dof"), "-o", str(out), "--chunk"]
    assert argv[5] == "1/1"
    assert run_script(after, tmp_path)[1:] == ["--check", "--job-dir", str(job_dir)]
    for where in (tmp_path, folder, job_dir):
        assert not (where / "PWNED").exists()


def test_a_dry_run_writes_renders_and_submits_nothing(scene, tmp_path, stub_sbatch):
    job_dir = tmp_path / "job"
    args = ["--chunk-size", "1", "--cpus", "1", "--job-dir", job_dir, scene, "--focus", "3",
            "-o", tmp_path / "out.#.exr"]
    run = submit("--dry-run", *args)
    assert run.returncode == 0, run.stderr
    assert "would write" in run.stdout and "#SBATCH --mem=<measured from frame 1>M" in run.stdout
    assert not job_dir.exists()
    assert sorted(os.listdir(tmp_path)) == ["sbatch"]
    # A job already there (its tasks may be queued) is left as it is.
    assert submit("--mem", "1G", *args).returncode == 0
    before = {name: (job_dir / name).read_bytes() for name in os.listdir(job_dir)}
    assert submit("--dry-run", "--fstop", "8", *args).returncode == 0
    assert {name: (job_dir / name).read_bytes() for name in os.listdir(job_dir)} == before
    assert len(os.listdir(stub_sbatch)) == 3  # the two scripts of the real submission


def test_resume_keeps_the_logs_of_the_chunks_it_resubmits(scene, tmp_path, stub_sbatch):
    job_dir = tmp_path / "job"
    args = ["--chunk-size", "1", "--cpus", "1", "--mem", "1G", "--job-dir", job_dir, scene,
            "--focus", "3", "-o", tmp_path / "out.#.exr"]
    assert submit(*args).returncode == 0
    assert sbatch_options((stub_sbatch / "script.1").read_text())["--output"].endswith(
        "/chunk_%a.log")
    (job_dir / "chunk_1.log").write_text("the first attempt's log")
    # Nothing was rendered (the stub runs nothing): --resume submits again.
    run = submit("--resume", *args)
    assert run.returncode == 0, run.stderr
    assert sbatch_options((stub_sbatch / "script.3").read_text())["--output"].endswith(
        "/chunk_%a.attempt2.log")
    assert (job_dir / "chunk_1.log").read_text() == "the first attempt's log"
    job = json.loads((job_dir / "job.json").read_text())
    assert job["attempt"] == 2 and job["logs"]["1"] == str(job_dir / "chunk_1.attempt2.log")
    check = submit("--check", "--job-dir", job_dir)
    assert check.returncode == 1 and f"chunk 1 (log {job_dir}/chunk_1.attempt2.log)" in check.stdout


def test_a_gap_in_the_input_sequence_is_refused(tmp_path):
    make = os.environ["MAKE_EXAMPLE_SCENE_BIN"]
    for frame in (1, 2, 4):
        subprocess.run([make, str(tmp_path / f"plate.{frame:04d}.exr"), "--width", "48",
                        "--height", "27"], check=True, capture_output=True)
    args = ["--dry-run", "--chunk-size", "2", "--mem", "1G", tmp_path / "plate.#.exr",
            "--focus", "3", "-o", tmp_path / "out.#.exr"]
    # It built a 3-frame job of a 4-frame range, and its check passed.
    run = submit(*args)
    assert run.returncode != 0
    assert "plate.0003.exr: no such file; frames with input files missing: 3" in run.stderr
    run = submit(*args, "--missing-frames", "skip")
    assert run.returncode == 0 and "(3 frames)" in run.stdout


def test_mem_takes_sizes_only(scene, tmp_path):
    for bad in ["infG", "nan", "0", "-1G", "0.0G", "1e400G", "lots", "2X"]:
        run = submit("--dry-run", "--chunk-size", "1", f"--mem={bad}", scene, "--focus", "3",
                     "-o", tmp_path / "out.#.exr")
        assert run.returncode != 0 and "Traceback" not in run.stderr, bad
        assert run.stderr.strip() == f"defocus-submit: --mem: '{bad}' is not a size (e.g. 4G, 800M)"
    run = submit("--dry-run", "--chunk-size", "1", "--mem", "1.5G", scene, "--focus", "3",
                 "-o", tmp_path / "out.#.exr")
    assert "#SBATCH --mem=1536M" in run.stdout


def test_what_every_task_would_refuse_is_refused_before_submitting(scene, tmp_path, stub_sbatch):
    base = ["--chunk-size", "4", "--cpus", "1", "--job-dir", tmp_path / "job", scene,
            "--focus", "3"]
    for dry in ([], ["--dry-run"]):
        # Twelve frames into one file.
        run = submit(*dry, "--mem", "1G", *base, "--frames", "1-12", "-o", tmp_path / "out.exr")
        assert run.returncode != 0
        assert run.stderr.strip().endswith(
            "out.exr: 12 frames need a frame pattern in the name, e.g. out.#.exr")
        # A memory limit no frame fits in (a frame of 640x360 needs 10 MB).
        big = tmp_path / "big.exr"
        if not big.exists():
            subprocess.run([os.environ["MAKE_EXAMPLE_SCENE_BIN"], str(big), "--width", "640",
                            "--height", "360"], check=True, capture_output=True)
        run = submit(*dry, "--mem", "1", "--chunk-size", "1", big, "--focus", "3", "-o",
                     tmp_path / "out.#.exr")
        assert run.returncode != 0
        assert "--mem 1M: " in run.stderr and "more than the memory limit of 1 MB" in run.stderr
    assert not (tmp_path / "job").exists() and not (tmp_path / "defocus-farm").exists()
    assert os.listdir(stub_sbatch) == ["sbatch"]


def test_a_new_submission_keeps_the_earlier_ones_logs(scene, tmp_path, stub_sbatch):
    job_dir = tmp_path / "job"
    args = ["--chunk-size", "1", "--cpus", "1", "--mem", "1G", "--job-dir", job_dir, scene,
            "--focus", "3", "-o", tmp_path / "out.#.exr"]
    assert submit(*args).returncode == 0
    (job_dir / "chunk_1.log").write_text("the first submission's log")
    run = submit(*args)
    assert run.returncode == 0, run.stderr
    assert f"the earlier submission's files are kept in {job_dir}/earlier.1" in run.stdout
    assert (job_dir / "earlier.1" / "chunk_1.log").read_text() == "the first submission's log"
    assert (job_dir / "earlier.1" / "job.json").exists()
    assert not (job_dir / "chunk_1.log").exists()


def test_resume_with_other_settings_says_so(scene, tmp_path, stub_sbatch):
    job_dir = tmp_path / "job"
    args = ["--chunk-size", "1", "--cpus", "1", "--mem", "1G", "--job-dir", job_dir, scene,
            "--focus", "3", "-o", tmp_path / "out.#.exr"]
    assert submit(*args).returncode == 0
    run = submit("--resume", *args)
    assert run.returncode == 0 and "other settings" not in run.stdout
    run = submit("--resume", *args, "--fstop", "8")
    assert run.returncode == 0, run.stderr
    assert ("--resume: the settings differ from the earlier submission's: every frame "
            "written with those is rendered again") in run.stdout
