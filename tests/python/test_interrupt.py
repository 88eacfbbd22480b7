"""Ctrl-C during a long library call: KeyboardInterrupt within a second, as from any Python code.

Before, SIGINT only set Python's flag, checked once the call returned with the GIL: an 8M-point insert
raised KeyboardInterrupt 4.6 s after the signal, a 20M-point one 15.6 s, and an interrupted OctoMap export
still wrote its file. Each case runs in a child process that signals itself, so a late interrupt cannot
land in the test runner.
"""
import os
import subprocess
import sys

import pytest

import occ_improve as oi

CHILD = r"""
import os, signal, sys, threading, time
import numpy as np
import occ_improve as oi
mapper = oi.Mapper(oi.kinect_v1_paper())
points = np.random.default_rng(0).uniform([-2, -2, 0.5], [2, 2, 7], (6_000_000, 3)).astype(np.float32)
{setup}
sent = []
def interrupt():
    sent.append(time.monotonic())
    os.kill(os.getpid(), signal.SIGINT)
threading.Timer(0.5, interrupt).start()
start = time.monotonic()
try:
    {call}
    print("completed", time.monotonic() - start, len(sent))
except KeyboardInterrupt:
    print("interrupted", time.monotonic() - sent[0])
print("afterwards", mapper.insert(points[:1000], threads=1).insertion.points_received)
"""


def run_child(call, setup=""):
    env = dict(os.environ)
    result = subprocess.run([sys.executable, "-c", CHILD.format(call=call, setup=setup)], env=env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return result.stdout.split("\n")


def test_ctrl_c_stops_a_long_insert_within_a_second_and_the_mapper_stays_usable():
    lines = run_child("mapper.insert(points, threads=1)")
    outcome, seconds = lines[0].split()
    assert outcome == "interrupted", lines
    assert float(seconds) < 1.0
    assert lines[1] == "afterwards 1000"


@pytest.mark.skipif(not oi.HAS_OCTOMAP, reason="built without the OctoMap adapter")
def test_ctrl_c_stops_an_octomap_export_and_writes_nothing(tmp_path):
    target = tmp_path / "stopped.ot"
    lines = run_child(f"mapper.export_octomap({str(target)!r}, 0.012, options=oi.OctomapExportOptions("
                      f"memory_cap_bytes=8 * 2**30))",
                      setup="mapper.insert(points[:300_000], threads=1)")
    outcome, seconds = lines[0].split()
    assert outcome == "interrupted", lines
    assert float(seconds) < 1.0
    assert not target.exists()


def test_an_ignored_sigint_or_a_programs_own_handler_is_left_alone():
    # A program that ignores SIGINT, or handles it itself, keeps its choice: the call runs to its end,
    # with the signal sent during it (the last field: signals sent before the call returned).
    lines = run_child("mapper.insert(points, threads=1)", setup="signal.signal(signal.SIGINT, signal.SIG_IGN)")
    assert lines[0].startswith("completed") and lines[0].split()[2] == "1", lines
    lines = run_child("mapper.insert(points, threads=1)",
                      setup="handled = []\nsignal.signal(signal.SIGINT, lambda *a: handled.append(1))")
    assert lines[0].startswith("completed") and lines[0].split()[2] == "1", lines


THREADED = r"""
import os, signal, threading, time
import numpy as np
import occ_improve as oi
mapper = oi.Mapper(oi.kinect_v1_paper())
points = np.random.default_rng(0).uniform([-2, -2, 0.5], [2, 2, 7], (6_000_000, 3)).astype(np.float32)
outcome = []
done = threading.Event()  # not join(): CPython 3.11's join() interrupted by KeyboardInterrupt may return early
def work():
    try:
        mapper.insert(points, threads=1)
        outcome.append("completed")
    except oi.Cancelled:
        outcome.append("cancelled")
    finally:
        done.set()
worker = threading.Thread(target=work)
worker.start()
threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
start = time.monotonic()
try:
    time.sleep(60)  # the main thread waits in a blocking call: Python's handler must wake it
    print("main not interrupted")
except KeyboardInterrupt:
    print("main interrupted" if time.monotonic() - start < 5 else "main interrupted late")
done.wait(30)
print("worker", outcome[0] if outcome else "still running")
"""


def test_ctrl_c_cancels_a_call_in_another_thread_and_interrupts_the_main_thread():
    # KeyboardInterrupt belongs to the main thread, as in Python, at once even in a blocking wait; the
    # worker's call ends with oi.Cancelled.
    result = subprocess.run([sys.executable, "-c", THREADED], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["main interrupted", "worker cancelled"], result.stdout


AT_EXIT = r"""
import os, signal, sys, threading, time
import numpy as np
import occ_improve as oi
mapper = oi.Mapper(oi.kinect_v1_paper())
points = np.random.default_rng(0).uniform([-2, -2, 0.5], [2, 2, 7], (6_000_000, 3)).astype(np.float32)
go, inserting = threading.Event(), threading.Event()
outcome = []
def work():
    go.wait()
    try:
        inserting.set()
        mapper.insert(points, threads=1)
        outcome.append("completed")
    except oi.Cancelled:
        outcome.append("cancelled")
worker = threading.Thread(target=work, daemon={daemon})
worker.start()
# Ctrl-C while the main thread waits in join(): CPython 3.11 then marks the worker as stopped, so the exit
# does not wait for it (as for a daemon thread).
timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
timer.daemon = True
timer.start()
try:
    worker.join()
except KeyboardInterrupt:
    pass
go.set()
inserting.wait()
time.sleep(0.3)  # the worker is inside its insert, without the GIL
# A second Ctrl-C stops the insert. From here the main thread keeps the GIL (no switch for 30 s, no
# blocking call), so the worker can take it back before the exit only if the exit waits for its call;
# else in the flush below, which finalization calls with the GIL released.
sys.setswitchinterval(30)
try:
    os.kill(os.getpid(), signal.SIGINT)
    while True:
        pass
except KeyboardInterrupt:
    pass
until = time.monotonic() + 0.5
while time.monotonic() < until:  # the insert is cancelled meanwhile, and waits for the GIL
    pass
class FlushedAtFinalization:
    def write(self, text):
        return sys.__stdout__.write(text)
    def flush(self, sleep=time.sleep, out=sys.__stdout__, finalizing=sys.is_finalizing):
        if finalizing():  # not the flush after the script: finalization's
            sleep(0.5)
            out.write(f"worker {{' '.join(outcome) or 'still running'}}\n")
            out.flush()
sys.stdout = FlushedAtFinalization()
"""


@pytest.mark.parametrize("daemon", [False, True], ids=["joined", "daemon"])
def test_a_call_still_running_at_exit_is_cancelled_before_finalization(daemon):
    # Ctrl-C in join() (the main thread's KeyboardInterrupt ends the program) with a worker inside a call:
    # the call ended while the interpreter finalized, its thread taking the GIL back was ended with
    # pthread_exit, which cannot unwind through the binding's C++ frames: "terminate called without an
    # active exception", status 134. The exit now cancels the call and waits for it first.
    result = subprocess.run([sys.executable, "-c", AT_EXIT.format(daemon=daemon)], capture_output=True, text=True,
                            timeout=120)
    assert "terminate called" not in result.stderr, result.stderr
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[0] == "worker cancelled", result.stdout
