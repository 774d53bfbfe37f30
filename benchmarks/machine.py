"""What every benchmark prints first: the machine and the versions it ran with."""

from __future__ import annotations

import os
import platform
from importlib.metadata import PackageNotFoundError, version


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def package_version(dist: str) -> str:
    try:
        return version(dist)
    except PackageNotFoundError:
        return "not installed"


def machine_lines(extra: tuple[str, ...] = ()) -> list[str]:
    """Platform, CPU, cores, load average, Python and the versions of the core packages (+ ``extra``)."""
    load = f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "?"
    packages = ("numpy", "pin", "proxsuite", *extra)
    try:  # the qprr that runs (a source tree may differ from the installed distribution)
        import qprr

        ours = f"qprr {qprr.__version__} ({os.path.dirname(qprr.__file__)})"
    except ImportError:
        ours = "qprr not importable"
    return [
        f"{platform.platform()}, Python {platform.python_version()}",
        f"CPU: {cpu_name()} ({os.cpu_count()} logical cores), load average {load}",
        ", ".join(f"{p} {package_version(p)}" for p in packages) + f", {ours}",
    ]
