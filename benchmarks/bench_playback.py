"""Playback cost of an animation in the app: the real window, OBSERVATION mode, the 3D view
(pyqtgraph's 3D view) playing examples/animated.json (16k vertices, 4 pins, 2 s loop) at
24 fps, on software OpenGL (Mesa llvmpipe) under Xvfb.

Run: .venv/bin/python benchmarks/bench_playback.py [--seconds 5] [--threads default,1,2]
     [--styles shaded,cel,isophotes] [--size 1280x800] [--shots DIR]

It starts its own Xvfb (unless DISPLAY is set: then that X server is used, e.g. under
``xvfb-run -a``) and runs the app in one child process per setting: each LP_NUM_THREADS value
(llvmpipe's rasteriser threads; "default" leaves it unset: one per core) in the shaded style,
then each other display style with the default threads. Each child loads the document,
switches to OBSERVATION, waits for the first pose, presses Play, lets the loop run for a
second, then measures SECONDS of playback. Printed per setting (figures only, no assertions):

- process CPU per shown frame (``time.process_time``: every thread of the process), and the
  share of the main (GUI) thread, the pose worker, llvmpipe's threads and the rest (per-thread
  CPU from /proc/self/task/*/schedstat);
- the X server's CPU per shown frame, when the script started Xvfb itself (the pixels the
  app sends to the screen cost there, outside the app's process);
- frames shown per second (a frame is shown when the model is drawn with a pose it was not
  drawn with before), timer ticks per second;
- per shown frame: draws of the model (renders of the 3D scene), repaints of the view on
  screen (the view's ``frameSwapped`` signal) and ``set_positions`` calls;
- the load average before and after (the machine is shared: CPU time, not wall time, is the
  figure to compare; wall-clock figures such as frames per second drop under load).

With ``--shots DIR`` the first child also steps the loop frame by frame (0, 1, ... 12, each
pose waited for, so the pictures do not depend on timing) and saves the 3D view at frame 12
in each display style (shaded, cel, isophotes) as DIR/frame12_<style>.png, the whole window
(shaded) as DIR/frame12_window.png, and the pose as DIR/frame12_pose.npy (to compare two
versions of the app: the pose must be the same bits, the pictures the same pixels).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "animated.json"


# --- the child: the app playing ------------------------------------------------------------------
def _thread_times() -> dict[int, tuple[str, float]]:
    """{tid: (name, CPU seconds)} of this process' threads (Linux /proc)."""
    out = {}
    for task in Path("/proc/self/task").iterdir():
        try:
            ns = int((task / "schedstat").read_text().split()[0])
            name = (task / "comm").read_text().strip()
        except (OSError, ValueError, IndexError):
            continue  # a thread that just ended
        out[int(task.name)] = (name, ns * 1e-9)
    return out


def _run_loop(app, ms: int) -> None:
    from PySide6.QtCore import QEventLoop, QTimer

    loop = QEventLoop()
    QTimer.singleShot(ms, loop.quit)
    loop.exec()


def _wait(app, cond, timeout_s: float = 120.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            raise SystemExit("timed out waiting for the app")
        app.processEvents()
        time.sleep(0.005)


def _xserver_cpu() -> float | None:
    """CPU seconds used so far by the X server this script started (None: not ours)."""
    pid = os.environ.get("BENCH_PLAYBACK_XVFB_PID")
    if not pid:
        return None
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


def _shots(app, w, ctl, out: Path) -> None:
    """The view at frame 12, reached one frame at a time, in each display style."""
    import numpy as np

    ctl.set_playing(False)
    for f in range(13):
        # each frame warm-starts from the pose on display: wait for this one to arrive
        shown = ctl._pose
        ctl.set_frame(f)
        _wait(app, lambda: ctl._pose is not shown and ctl.worker._pending is None and not ctl.worker.busy)  # noqa: B023 - called in this iteration
    _run_loop(app, 200)
    out.mkdir(parents=True, exist_ok=True)
    for style in ("shaded", "cel", "isophotes"):
        w.view3d.set_style(style, 8)
        _run_loop(app, 200)
        w.view3d.gl.grabFramebuffer().save(str(out / f"frame12_{style}.png"))
        if style == "shaded":
            w.grab().save(str(out / "frame12_window.png"))
    w.view3d.set_style("shaded", 8)
    np.save(out / "frame12_pose.npy", ctl._pose)


def child(seconds: float, size: tuple[int, int], style: str, shots: str | None) -> None:
    import numpy as np

    from sketchforge.document import fileformat as ff
    from sketchforge.document.document import Document
    from sketchforge.qt.app import ensure_qapp, plugin_host, settle
    from sketchforge.qt.main_window import MainWindow

    app = ensure_qapp()
    host = plugin_host()
    w = MainWindow(Document(host=host), host=host)
    w.resize(*size)
    w.adopt(ff.load(EXAMPLE, host=host), None)
    w.show()
    w.set_mode("observation")
    settle(w, app)
    panel = w.plugin_panels["animation"]
    ctl = panel.c
    _wait(app, lambda: w.view3d.model_item is not None and ctl._animator is not None  # the first pose arrived
          and ctl.worker._pending is None and not ctl.worker.busy)
    _run_loop(app, 300)
    if shots:
        _shots(app, w, ctl, Path(shots))
        ctl.set_frame(0)
    w.view3d.set_style(style, 8)

    item = w.view3d.model_item
    gl = w.view3d.gl
    n = {"draws": 0, "shown": 0, "repaints": 0, "set_positions": 0, "ticks": 0}
    fresh = [False]
    draw, set_positions = item.paint, item.set_positions

    def counted_draw():
        n["draws"] += 1
        if fresh[0]:
            n["shown"] += 1
            fresh[0] = False
        draw()

    def counted_set_positions(P):
        n["set_positions"] += 1
        fresh[0] = True
        set_positions(P)

    item.paint = counted_draw  # pyqtgraph calls item.paint() from Python: the instance wins
    item.set_positions = counted_set_positions
    gl.frameSwapped.connect(lambda: n.__setitem__("repaints", n["repaints"] + 1))
    ctl.timer.timeout.connect(lambda: n.__setitem__("ticks", n["ticks"] + 1))

    panel.play.setChecked(True)  # what a user presses
    if not ctl.playing:
        raise SystemExit("playback did not start")
    _run_loop(app, 1000)  # warm up: the first frames after Play
    load0 = os.getloadavg()
    main_tid = __import__("threading").main_thread().native_id
    worker_tid = ctl.worker._thread.native_id
    print(f"measuring {seconds:g} s of playback (pid {os.getpid()})", file=sys.stderr, flush=True)
    c0, t0, th0, n0, x0 = time.process_time(), time.perf_counter(), _thread_times(), dict(n), _xserver_cpu()
    _run_loop(app, int(1000 * seconds))
    c1, t1, th1, n1, x1 = time.process_time(), time.perf_counter(), _thread_times(), dict(n), _xserver_cpu()
    load1 = os.getloadavg()
    panel.play.setChecked(False)

    d = {k: n1[k] - n0[k] for k in n1}
    shares = {"main": 0.0, "pose": 0.0, "llvmpipe": 0.0, "other": 0.0}
    for tid, (name, cpu) in th1.items():
        used = cpu - th0.get(tid, (name, 0.0))[1]
        key = ("main" if tid == main_tid else "pose" if tid == worker_tid
               else "llvmpipe" if name.startswith("llvmpipe") else "other")
        shares[key] += used
    frames = max(d["shown"], 1)
    result = {
        "lp_threads": os.environ.get("LP_NUM_THREADS", "default"),
        "style": style,
        "llvmpipe_threads": sum(1 for name, _ in th1.values() if name.startswith("llvmpipe")),
        "seconds": t1 - t0,
        "cpu_per_frame_ms": 1e3 * (c1 - c0) / frames,
        "share_ms": {k: 1e3 * v / frames for k, v in shares.items()},
        "xserver_ms": None if x0 is None else 1e3 * (x1 - x0) / frames,
        "shown_per_s": d["shown"] / (t1 - t0),
        "ticks_per_s": d["ticks"] / (t1 - t0),
        "draws_per_frame": d["draws"] / frames,
        "repaints_per_frame": d["repaints"] / frames,
        "set_positions_per_frame": d["set_positions"] / frames,
        "cpu_share_of_wall": (c1 - c0) / (t1 - t0),
        "load": [round(load0[0], 2), round(load1[0], 2)],
        "vertices": int(len(ctl.mesh.V)),
        "triangles": int(len(ctl.mesh.F)),
        "view": [gl.width(), gl.height()],
    }
    del np
    print("RESULT " + json.dumps(result), flush=True)
    w.close_now()


# --- the parent: Xvfb, one child per setting, the table ------------------------------------------
def _start_xvfb() -> tuple[subprocess.Popen, str] | None:
    if shutil.which("Xvfb") is None:
        return None
    r, wfd = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(wfd), "-screen", "0", "1920x1200x24", "-nolisten", "tcp"],
                            pass_fds=(wfd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(wfd)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    if not number:
        proc.kill()
        raise SystemExit("Xvfb did not start")
    return proc, f":{number}"


def _settings(threads: str, styles: str) -> list[tuple[str, str]]:
    """(LP_NUM_THREADS, style): every thread setting in the first style, the other styles
    with the first thread setting."""
    threads_, styles_ = threads.split(","), styles.split(",")
    return [(t, styles_[0]) for t in threads_] + [(threads_[0], s) for s in styles_[1:]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="measured playback per setting")
    ap.add_argument("--threads", default="default,1,2", help="LP_NUM_THREADS settings, comma-separated")
    ap.add_argument("--styles", default="shaded,cel,isophotes", help="display styles, comma-separated")
    ap.add_argument("--size", default="1280x800", help="window size (the app's default)")
    ap.add_argument("--shots", default=None, help="save the view at frame 12 in each style here")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--style", default="shaded", help=argparse.SUPPRESS)
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    if args.child:
        child(args.seconds, size, args.style, args.shots)
        return
    xvfb = None
    env = dict(os.environ, QT_QPA_PLATFORM="xcb")
    env.setdefault("QT_LOGGING_RULES", "qt.qpa.*=false")
    env.pop("BENCH_PLAYBACK_XVFB_PID", None)
    if not env.get("DISPLAY"):
        started = _start_xvfb()
        if started is None:  # `make bench` goes on with the other benchmarks
            print("bench_playback: skipped, no X server: install Xvfb (apt install xvfb) or set DISPLAY")
            return
        xvfb, env["DISPLAY"] = started
        env["BENCH_PLAYBACK_XVFB_PID"] = str(xvfb.pid)
    try:
        print(f"{EXAMPLE.name}, window {size[0]}x{size[1]}, {args.seconds:g} s of playback per setting, "
              f"{os.cpu_count()} cores, DISPLAY {env['DISPLAY']}" + (" (Xvfb started here)" if xvfb else ""))
        rows = []
        for i, (threads, style) in enumerate(_settings(args.threads, args.styles)):
            cenv = dict(env)
            cenv.pop("LP_NUM_THREADS", None)
            if threads != "default":
                cenv["LP_NUM_THREADS"] = threads
            cmd = [sys.executable, __file__, "--child", "--seconds", str(args.seconds), "--size", args.size,
                   "--style", style]
            if args.shots and i == 0:
                cmd += ["--shots", args.shots]
            proc = subprocess.run(cmd, env=cenv, capture_output=True, text=True, timeout=600)
            line = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
            if proc.returncode != 0 or not line:
                print(f"LP_NUM_THREADS={threads}, {style}: the app failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
                continue
            rows.append(json.loads(line[0][7:]))
        if rows:
            r = rows[0]
            print(f"model: {r['vertices']} vertices, {r['triangles']} triangles; 3D view {r['view'][0]}x{r['view'][1]} px")
        print(f"{'style':>9} {'LP_NUM_THREADS':>14} {'CPU/frame':>10} {'main':>6} {'pose':>6} {'llvmpipe':>8} "
              f"{'other':>6} {'X server':>8} {'shown/s':>8} {'ticks/s':>8} {'draws':>6} {'repaints':>8} "
              f"{'set_pos':>7} {'CPU/wall':>8} {'load':>11}")
        for r in rows:
            s = r["share_ms"]
            xs = "n/a" if r["xserver_ms"] is None else f"{r['xserver_ms']:.1f}"
            print(f"{r['style']:>9} {r['lp_threads'] + ' (' + str(r['llvmpipe_threads']) + ')':>14} "
                  f"{r['cpu_per_frame_ms']:8.1f}ms {s['main']:6.1f} {s['pose']:6.1f} {s['llvmpipe']:8.1f} "
                  f"{s['other']:6.1f} {xs:>8} {r['shown_per_s']:8.1f} {r['ticks_per_s']:8.1f} "
                  f"{r['draws_per_frame']:6.2f} {r['repaints_per_frame']:8.2f} {r['set_positions_per_frame']:7.2f} "
                  f"{r['cpu_share_of_wall']:8.2f} {r['load'][0]:5.1f}-{r['load'][1]:<5.1f}")
        print("(CPU/frame: the app's process CPU per shown frame, ms; main/pose/llvmpipe/other: its split by "
              "thread, ms; X server: Xvfb's CPU per shown frame, ms, not in CPU/frame; draws, repaints, set_pos: "
              "per shown frame; CPU/wall: cores the app kept busy; load: 1-min load average before-after; "
              "LP_NUM_THREADS (n): n llvmpipe threads)")
    finally:
        if xvfb is not None:
            xvfb.terminate()
            xvfb.wait(10)


if __name__ == "__main__":
    main()
