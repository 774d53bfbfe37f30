"""The text summary of a flight log (``qprr log show``): the vehicle, the duration, the phases, the topics with
their rates and the parameters of note."""

from __future__ import annotations

from .phases import Phases
from .ulog import FlightLog

PARAMETERS_OF_NOTE = ("CA_AIRFRAME", "CA_ROTOR_COUNT", "MPC_THR_HOVER", "MPC_THR_MIN", "THR_MDL_FAC", "SDLOG_PROFILE")

# the type byte of ver_sw_release (PX4 src/lib/version/version.h: FIRMWARE_TYPE_*)
_RELEASE_TYPES = {0: "dev", 64: "alpha", 128: "beta", 192: "rc", 255: "release"}


def software_version(info: dict[str, str]) -> str:
    """PX4's version from ``ver_sw_release`` (0xMMmmppTT: major, minor, patch, type) and the ``ver_sw`` git hash."""
    text = info.get("ver_sw_release", "")
    git = info.get("ver_sw", "")[:8]
    try:
        v = int(text)
    except ValueError:
        return git or "unknown"
    major, minor, patch, kind = (v >> 24) & 0xFF, (v >> 16) & 0xFF, (v >> 8) & 0xFF, v & 0xFF
    if major == 0 and minor == 0 and patch == 0:
        return git or "unknown"
    label = _RELEASE_TYPES.get(kind, f"type {kind}")
    return f"v{major}.{minor}.{patch} {label}" + (f" ({git})" if git else "")


def topic_lines(log: FlightLog, width: int = 110) -> list[str]:
    """The topics sorted by name, instances grouped (``sensor_baro[0,1]``), each with its rate [Hz], wrapped."""
    grouped: dict[str, list] = {}
    for info in log.topics():
        grouped.setdefault(info.name, []).append(info)
    items = []
    for name, infos in grouped.items():
        ids = "" if len(infos) == 1 and infos[0].multi_id == 0 else "[" + ",".join(str(i.multi_id) for i in infos) + "]"
        rate = infos[0].rate_hz
        items.append(f"{name}{ids} {rate:.3g} Hz" if rate > 0 else f"{name}{ids} ({infos[0].samples} samples)")
    lines, line = [], "  "
    for item in items:
        if len(line) + len(item) + 2 > width and line.strip():
            lines.append(line.rstrip())
            line = "  "
        line += item + ", "
    lines.append(line.rstrip(", "))
    return lines


def show_lines(log: FlightLog, phases: Phases) -> list[str]:
    """The lines ``qprr log show`` prints."""
    info = log.info
    vehicle = f"{info.get('sys_name', '?')} on {info.get('ver_hw', '?')}, software {software_version(info)}"
    lines = [
        f"log       {log.path}",
        f"vehicle   {vehicle}, airframe {log.airframe if log.airframe is not None else 'unknown'} (SYS_AUTOSTART)",
        f"duration  {log.duration_s:.1f} s",
        "phases",
        *(f"  {line}" for line in phases.lines()),
    ]
    if phases.takeoff_s is not None and phases.landing_s is not None:
        lines.insert(-len(phases.lines()) + 1, f"  take-off {phases.takeoff_s:.2f} s, landing {phases.landing_s:.2f} s")
    noted = [f"{k} {log.parameters[k]:g}" for k in PARAMETERS_OF_NOTE if k in log.parameters]
    lines.append("parameters  " + (", ".join(noted) if noted else "none of " + ", ".join(PARAMETERS_OF_NOTE)))
    lines.append(f"changed in flight  {len(log.changed_parameters)} parameter(s)")
    lines.append(f"topics ({len(log.topics())} instances)")
    lines += topic_lines(log)
    return lines


__all__ = ["PARAMETERS_OF_NOTE", "show_lines", "software_version", "topic_lines"]
