"""The lines `lagcomp run` and `lagcomp sweep` print about events that change the state (issue 21).

An event with a reset, or a contact's impact, is listed occurrence by occurrence: its time, for a contact
the impulses of the contacts that took part, and what the reset changed (each coordinate or velocity that
jumped, before → after).  A bouncing ball has hundreds of impacts, so a long list shows its first
`FIRST_SHOWN` and its last occurrence with the count of those left out between.  A sweep's summary gives,
per such event, the range of the impulses over the occurrences it kept.
"""

from __future__ import annotations

import numpy as np

#: Occurrences listed at the start of a long list (then "... k more ..." and the last one).
FIRST_SHOWN = 5
#: Jumps shown per occurrence (then "+k more"): a reset of many coordinates stays one line.
CHANGES_SHOWN = 3
#: The indent of `lagcomp run`'s continuation lines (its labels are 12 characters wide).
INDENT = " " * 12


def _changes(names, before: np.ndarray, after: np.ndarray) -> str:
    """``name before → after`` for each state component that jumped, the first `CHANGES_SHOWN` of them."""
    jumped = [f"{name} {b:.8g} → {a:.8g}" for name, b, a in zip(names, before, after, strict=True) if a != b]
    if len(jumped) > CHANGES_SHOWN:
        jumped = [*jumped[:CHANGES_SHOWN], f"+{len(jumped) - CHANGES_SHOWN} more"]
    return ", ".join(jumped) if jumped else "no jump"


def _impulses(contacts, values: np.ndarray) -> str:
    """``impulse c 1.25, d 0.5``: the contacts that pushed (non-zero impulse)."""
    pushed = [f"{name} {value:.6g}" for name, value in zip(contacts, values, strict=True) if value != 0]
    return "impulse " + (", ".join(pushed) if pushed else "0")


def _aligned(rows: list[list[str]]) -> list[str]:
    """Rows of cells as lines, each column padded to its widest cell."""
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    return ["   ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip() for row in rows]


def _switch_text(switch) -> str:
    """``floor closes``, ``floor lifts off``, ``belt sticks``, ``belt slips (v < 0)``: one mode switch."""
    if hasattr(switch, "contact"):
        return f"{switch.contact} {'closes' if switch.closed else 'lifts off'}"
    return f"{switch.friction} " + ("sticks" if switch.mode == 0 else f"slips (v {'>' if switch.mode > 0 else '<'} 0)")


def _switches_at(switches, t: float) -> str:
    """The mode switches at `t` (`Solution.contact_switches`, ``friction_switches``; an impact of one contact may
    close another), comma-separated."""
    return ", ".join(_switch_text(s) for s in switches if s.t == t)


def occurrence_lines(record, state_names, contacts, switches=()) -> list[str]:
    """The occurrences of one event of a `Solution` that changes the state (``record.jumps``, or a contact's
    impacts: ``record.impulses``), one line each, aligned; [] for other events.  `state_names` names the
    columns of (q, q̇) (`Solution.state_names`), `contacts` the columns of the impulses (`Model.contacts`);
    `switches` (`Solution.contact_switches` and ``friction_switches``) marks the occurrences at which contacts
    closed or lifted off and friction elements began to stick or slip (those events are listed too)."""
    switching = any(s.t in record.t for s in switches)
    if len(record) == 0 or not (record.impulses is not None or record.jumps or switching):
        return []
    before = np.hstack([record.q, record.qd])
    after = np.hstack([record.q_after, record.qd_after])
    count = len(record)
    shown = list(range(count)) if count <= FIRST_SHOWN + 2 else [*range(FIRST_SHOWN), count - 1]
    rows = []
    for k in shown:
        row = [f"#{k + 1}", f"t = {record.t[k]:.10g}"]
        if record.impulses is not None:
            row.append(_impulses(contacts, record.impulses[k]))
        rows.append([*row, _changes(state_names, before[k], after[k]), _switches_at(switches, record.t[k])])
    lines = [INDENT + line for line in _aligned(rows)]
    if len(shown) < count:
        lines.insert(FIRST_SHOWN, f"{INDENT}... {count - len(shown)} more ...")
    return lines


def sweep_event_summary(record, contacts) -> str:
    """What a sweep's record of one event (`Sweep.events`) adds to its count: whether it resets the state, and
    for a contact the range of each contact's impulses over the occurrences kept (`event_cap` per trajectory)."""
    if "y_after" not in record:
        return ""
    if "impulses" not in record:
        return " (each resets the state)"
    impulses = record["impulses"].reshape(-1, len(contacts))
    kept = impulses[~np.isnan(impulses).any(axis=1)]
    if not kept.size:
        return " (impacts)"
    ranges = (f"{name} {kept[:, c].min():.6g} .. {kept[:, c].max():.6g}" for c, name in enumerate(contacts))
    return f" (impacts); impulses over the {kept.shape[0]} kept: " + ", ".join(ranges)
