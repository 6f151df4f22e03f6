"""Ctrl-C (SIGINT) during a render raises KeyboardInterrupt after the current iteration and
leaves the session usable; rendering releases the interpreter's lock."""

import signal
import subprocess
import sys
import textwrap
import threading
import time

import vcm

SCRIPT = textwrap.dedent(
    """
    import vcm
    session = vcm.Session(vcm.load_file("cornell-sun"), algorithm="{algorithm}", resolution=(64, 64))
    session.step()
    print("ready", flush=True)
    try:
        session.step(1000000)
        print("not interrupted", flush=True)
    except KeyboardInterrupt:
        print("interrupted", session.iterations, flush=True)
    before = session.iterations
    session.step(2)
    print("usable", session.iterations - before, flush=True)
    try:
        vcm.render(vcm.load_file("cornell-sun"), iterations=1000000, resolution=(64, 64))
    except KeyboardInterrupt:
        print("render interrupted", flush=True)
    """
)


def test_sigint_stops_after_the_iteration_and_keeps_the_session():
    for algorithm in ("pt", "vcm"):
        process = subprocess.Popen([sys.executable, "-c", SCRIPT.format(algorithm=algorithm)],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert process.stdout.readline().strip() == "ready"
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        line = process.stdout.readline().split()
        assert line[0] == "interrupted", (line, process.stderr.read())
        assert int(line[1]) >= 1
        assert process.stdout.readline().split() == ["usable", "2"]
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        output, errors = process.communicate(timeout=120)
        assert output.strip() == "render interrupted", errors
        assert process.returncode == 0, errors


def test_rendering_releases_the_interpreter_lock():
    scene = vcm.load_file("cornell-sun")
    thread = threading.Thread(target=vcm.render, args=(scene,), kwargs={"iterations": 12, "resolution": (96, 96)})
    thread.start()
    ticks = 0
    while thread.is_alive():
        ticks += 1
        time.sleep(0.002)
    thread.join()
    # With the lock held for the whole render this loop would run only before and after it.
    assert ticks >= 20, ticks
