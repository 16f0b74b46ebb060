"""A render releases the GIL, renders from several threads give the same bits, and Ctrl-C
stops a render at its next pass with KeyboardInterrupt."""

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import meshtrace as mt


def test_other_threads_run_while_it_renders(cpu):
    scene = mt.load("builtin:cornell")
    done = threading.Event()
    result = {}

    def work():
        result["out"] = cpu.render(scene, spp=64, width=128, height=96)
        done.set()

    worker = threading.Thread(target=work)
    began = time.perf_counter()
    worker.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    took = time.perf_counter() - began
    # Holding the GIL would stall this loop for the whole render.
    assert took > 0.05 and ticks > 0.2 * took / 0.001, (ticks, took)
    assert result["out"]["color"].shape == (96, 128, 3)


def test_renders_in_threads_give_the_same_bits(cpu):
    scene = mt.load("builtin:cornell")
    alone = cpu.render(scene, spp=8, width=48, height=32)["color"]
    outs = [None] * 4

    def work(i):
        outs[i] = cpu.render(scene, spp=8, width=48, height=32)["color"]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(np.array_equal(o, alone) for o in outs)


def test_ctrl_c_stops_a_render():
    script = textwrap.dedent(
        """
        import os, signal, threading, time
        import meshtrace as mt
        # A job that a shell starts in the background without job control (`cmd &` in a
        # script, as CI runners may) inherits SIGINT ignored, which Python keeps: handle it
        # as an interactive session does.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        r = mt.Renderer(device="cpu")
        scene = mt.load("builtin:cornell")
        # One pass of the CPU renderer: 2^20 paths, 64 spp at 128×128.
        began = time.perf_counter()
        r.render(scene, spp=64, width=128, height=128)
        one_pass = time.perf_counter() - began
        threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()
        began = time.perf_counter()
        try:
            r.render(scene, spp=100000, width=128, height=128)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted", time.perf_counter() - began, one_pass)
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    word, seconds, one_pass = done.stdout.split()
    assert word == "interrupted"
    # Signalled after 1 s, it stops at the end of the pass under way.
    assert float(seconds) < 1.0 + 2.0 * float(one_pass) + 0.5, (seconds, one_pass)
