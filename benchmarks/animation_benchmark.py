"""Wall time of a 30 s animation: a 1 kHz run of 30 s (30 001 samples, a simulator's size) to GIF and, with ffmpeg, MP4.

The run is the demo IK path of ``qprr animate`` (end-effector circle with a pitching tool, the IK
solved at 20 Hz, linearly interpolated to 1 kHz, hover thrusts logged).  Before timing, the
benchmark checks the decimation (601 frames at 20 fps) and the file (frame count, frame time).

    python benchmarks/animation_benchmark.py [--platform q-prr] [--repeat 1] [--quick]

Prints the ratio of each file's wall time to the run's length (1: as fast as real time).
``--quick``: a 2 s run (41 frames), GIF only: a smoke run of a few seconds.
"""

from __future__ import annotations

import argparse
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from machine import machine_lines

import qprr
from qprr.platforms import resolve as platform_from_name
from qprr.viz import RunLog, animate_result
from qprr.viz.cli import demo_run


def one_khz(run: RunLog, rate: float = 1000.0) -> RunLog:
    """The run resampled at ``rate`` by linear interpolation (a simulator's log size)."""
    t = np.arange(int(round((run.t[-1] - run.t[0]) * rate)) + 1) / rate + run.t[0]
    xi = np.stack([np.interp(t, run.t, c) for c in run.xi.T], axis=1)
    f = np.stack([np.interp(t, run.t, c) for c in run.f.T], axis=1)
    return RunLog(t, xi, f=f, platform=run.platform)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--platform", default="q-prr")
    parser.add_argument("--repeat", type=int, default=1, help="timed repetitions per format (median reported)")
    parser.add_argument("--quick", action="store_true", help="a 2 s run, GIF only (a smoke run)")
    args = parser.parse_args(argv)
    print("\n".join(machine_lines(("matplotlib", "pillow"))))
    print(f"ffmpeg: {shutil.which('ffmpeg') or 'not installed'}")
    platform = platform_from_name(args.platform)
    seconds = 2.0 if args.quick else 30.0
    frames = int(round(20 * seconds)) + 1  # 20 fps, both ends
    t0 = time.perf_counter()
    run = one_khz(demo_run(platform, seconds, 20.0))
    print(f"run: {platform.name}, {run.n} samples over {run.t[-1] - run.t[0]:.1f} s (IK path built in {time.perf_counter() - t0:.1f} s)")

    from PIL import Image

    formats = [".gif"] + ([".mp4"] if shutil.which("ffmpeg") and not args.quick else [])
    with tempfile.TemporaryDirectory() as tmp:
        for suffix in formats:
            times = []
            for k in range(args.repeat):
                path = Path(tmp) / f"bench{k}{suffix}"
                info = animate_result(platform, run, path)
                times.append(info.wall_time)
                if suffix == ".gif":
                    with Image.open(path) as im:
                        assert im.n_frames == frames and im.info["duration"] == 50, (im.n_frames, im.info)
                assert info.frames == frames
                size = path.stat().st_size
            med = float(np.median(times))
            spread = f" (min {min(times):.1f}, max {max(times):.1f})" if len(times) > 1 else ""
            print(
                f"{suffix[1:]:>4}: {frames} frames 640x480 at 20 fps for {seconds:g} s of run: {med:.1f} s{spread}, "
                f"{size / 1e6:.1f} MB, {info.writer}; ratio wall time / run length {med / seconds:.2f}",
                flush=True,
            )
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory {peak:.0f} MB")
    print(f"(qprr {qprr.__version__})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
