"""The command line's argument types: each parses one option's text, or says in one
line what it takes (argparse turns the message into the usage error)."""

from __future__ import annotations

import argparse
import math

from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematics import Bearing, crowded


def number(kind, low=None, high=None, low_open=False, high_open=False):
    """An argparse type: a finite ``kind`` within the bounds, else a message naming them."""
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError as err:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"'{text}' is not {what}") from err
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"'{text}' is not a finite number")
        if low is not None and (value <= low if low_open else value < low):
            raise argparse.ArgumentTypeError(f"{text} must be {'>' if low_open else '>='} {low}")
        if high is not None and (value >= high if high_open else value > high):
            raise argparse.ArgumentTypeError(f"{text} must be {'<' if high_open else '<='} {high}")
        return value
    return parse


positive = number(float, 0, low_open=True)
rate = number(float, 0, 1, low_open=True, high_open=True)


def parameter_value(text: str) -> tuple[str, float]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"takes NAME=VALUE, got '{text}'")
    return name.strip(), number(float)(value)


def bearing(text: str) -> Bearing:
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) not in (3, 4) or not all(math.isfinite(p) for p in parts):
        raise argparse.ArgumentTypeError(f"takes N_BALLS,BALL_MM,PITCH_MM[,ANGLE_DEG], got '{text}'")
    n, d_mm, pitch_mm = parts[:3]
    angle = parts[3] if len(parts) > 3 else 0.0
    if n != int(n) or n < 1:
        raise argparse.ArgumentTypeError(f"the number of balls must be a positive integer, got {n:g}")
    if not 0 < d_mm < pitch_mm:
        raise argparse.ArgumentTypeError(f"need 0 < ball diameter < pitch diameter, got {d_mm:g} "
                                         f"and {pitch_mm:g} mm")
    if why := crowded(int(n), d_mm, pitch_mm):
        raise argparse.ArgumentTypeError(why)
    if not 0 <= angle < 90:
        raise argparse.ArgumentTypeError(f"the contact angle must lie in [0, 90) degrees, got {angle:g}")
    return Bearing(int(n), d_mm * 1e-3, pitch_mm * 1e-3, math.radians(angle))


def sensitivity(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"takes NAME=SENSITIVITY (e.g. ch1=100mV/g), got "
                                         f"'{text}'")
    return name.strip(), value.strip()


def speed_ratio(text: str) -> float:
    """A speed ratio: a number, a fraction, or a product of them (``14/21*19/47``)."""
    try:
        value = 1.0
        for factor in text.split("*"):
            num, sep, den = factor.partition("/")
            value *= float(num) / float(den) if sep else float(num)
    except (ValueError, ZeroDivisionError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"takes a positive speed ratio (e.g. 1.706, 29/17 or "
                                         f"14/21*19/47), got '{text}'")
    return value


def teeth(text: str) -> tuple[int, int]:
    parts = text.split(",")
    try:
        values = [int(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 2 or min(values) < 2:
        raise argparse.ArgumentTypeError(f"takes NP,NG (pinion and gear teeth, whole "
                                         f"numbers of at least 2), got '{text}'")
    return values[0], values[1]


def effect_list(text: str) -> list[str]:
    """Comma-separated effect keys; "none" for none."""
    if text.strip() == "none":
        return []
    keys = [k.strip() for k in text.split(",") if k.strip()]
    unknown = [k for k in keys if k not in EFFECTS]
    if unknown or not keys:
        raise argparse.ArgumentTypeError(f"unknown effect(s) {', '.join(unknown) or '(none)'}; "
                                         f"known: {', '.join(EFFECTS)}")
    return keys
