"""A program's own experiment stopped with Ctrl-C and resumed (the examples' test; the kill test
is kill_resume_index.cmake).

    interrupt_resume.py WORK_DIR STOP_AT RESUME_TEXT PROGRAM [ARGUMENT …] -- [RUN_OPTION …]

Runs PROGRAM (with its first ARGUMENTs) whole into WORK_DIR/whole; runs it again into
WORK_DIR/part, stopped (SIGSTOP, by the run layer's fault point PHYSGRAD_FAULT=stop@STOP_AT) at a
known step and sent a real SIGINT there; that run must exit with status 130, keep its checkpoint
and print the folder and RESUME_TEXT (the program's own resume command). The resumed run must
end with the final losses of the whole run. Any failing step exits 1 with what failed.
"""
import os
import shutil
import signal
import subprocess
import sys
import time


def fail(what):
    print("interrupt_resume:", what, file=sys.stderr)
    sys.exit(1)


def start(program, arguments, fault=None):
    env = dict(os.environ)
    env.pop("PHYSGRAD_FAULT", None)
    if fault:
        env["PHYSGRAD_FAULT"] = fault
    return subprocess.Popen(program + arguments, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def finish(process, what):
    out, err = process.communicate(timeout=600)
    print(f"{what}: {process.returncode}\n{out}{err}")
    return process.returncode, out


def finals(output):
    return [line for line in output.splitlines() if " final test loss " in line]


def state(pid):
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0]


def main(argv):
    work, stop_at, resume_text = argv[1], argv[2], argv[3]
    split = argv.index("--")
    program, options = argv[4:split], argv[split + 1:]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    whole_dir, part_dir = os.path.join(work, "whole"), os.path.join(work, "part")

    status, out = finish(start(program, ["run", whole_dir] + options), "whole run")
    whole = finals(out)
    if status != 0 or not whole:
        fail("the whole run failed or printed no final test loss")

    process = start(program, ["run", part_dir] + options, fault="stop@" + stop_at)
    deadline = time.monotonic() + 300
    while state(process.pid) != "T":
        if process.poll() is not None or time.monotonic() > deadline:
            finish(process, "run to interrupt")
            fail(f"the run did not stop at {stop_at}")
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGINT)
    os.kill(process.pid, signal.SIGCONT)
    status, out = finish(process, "interrupted run")
    if status != 130:
        fail(f"the interrupted run exited with {status}, expected 130")
    if resume_text not in out or part_dir not in out or "checkpoint kept" not in out:
        fail(f"the interrupted run did not print its folder, '{resume_text}' and 'checkpoint "
             "kept'")
    if not os.path.exists(os.path.join(part_dir, "checkpoint.pgc")):
        fail("the interrupted run's folder holds no checkpoint")

    status, out = finish(start(program, ["resume", part_dir]), "resumed run")
    if status != 0 or finals(out) != whole:
        fail(f"the resumed run ended with {finals(out)}, the whole run with {whole}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
