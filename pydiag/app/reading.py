"""A record read as the command line's reading options say (channels, units, rate,
sensitivities, the tacho's channel)."""

from __future__ import annotations

import sys

from pydiag.core.errors import UsageError
from pydiag.core.measurement import Measurement
from pydiag.io.readers import read_measurement


def channels_to_read(args) -> list[str] | None:
    """The --channel specs, with the tacho channel added when channels are chosen."""
    chosen = list(args.channel or [])
    if chosen and args.tacho and args.tacho not in [c.partition("=")[0] for c in chosen]:
        chosen.append(args.tacho)
    return chosen or None


def read_input(args, path: str | None = None) -> Measurement:
    """The record ``path`` (default ``--measurement``) as the options say to read it; a
    sensitivity given for the tacho's channel is refused (its pulses are no sensor's)."""
    tacho = getattr(args, "tacho", None)
    if tacho and tacho in dict(getattr(args, "sensitivity", None) or []):
        raise UsageError(f"--sensitivity names {tacho}, the tacho's channel: a tacho's pulses "
                         "are counted, not converted (give the sensors' channels)")
    m = read_measurement(path or args.measurement, args.sample_rate, channels_to_read(args),
                         args.unit, dict(getattr(args, "sensitivity", None) or []))
    for note in m.metadata.get("read_notes", []):  # what the reader would have us know
        print(f"pydiag {args.command}: warning: {path or args.measurement}: {note}",
              file=sys.stderr)
    return m
