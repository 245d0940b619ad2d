"""The lines `lagcomp run` prints about a finished run: energy, events, reactions and the final state."""

from __future__ import annotations


def run_lines(sol, model) -> list[str]:
    """The summary of `sol` (a run of `model`) after its status and timing lines, one string per line."""
    from lagcomp.event_report import occurrence_lines

    summary = sol.summary
    lines = [(f"energy      T+V: {sol.energy[0]:.12g} -> {sol.energy[-1]:.12g} "
              f"(max relative drift {summary.energy_error:.3g})"),
             (f"            h:   {sol.energy_function[0]:.12g} -> {sol.energy_function[-1]:.12g} "
              f"(max relative drift {summary.energy_function_error:.3g})")]
    lines += balance_lines(sol)
    for name, record in sol.events.items():
        when = f" at t = {record.t[0]:.10g}" + (f" .. {record.t[-1]:.10g}" if len(record) > 1 else "") \
            if len(record) else ""
        resets = " (impacts)" if record.impulses is not None else " (each resets the state)" if record.jumps else ""
        lines.append(f"event       {name}: {len(record)} occurrence(s){when}{resets if len(record) else ''}")
        lines += occurrence_lines(record, sol.state_names, model.contacts, sol.contact_switches + sol.friction_switches)
    for name, values in sol.reactions.items():
        lines.append(f"reaction    {name}: {values[0]:.8g} -> {values[-1]:.8g} "
                     f"(range {values.min():.6g} .. {values.max():.6g})")
    if sol.reactions:
        lines.append(f"            largest constraint residual {sol.constraint_residual:.3g}")
    lines.append(f"final       {', '.join(f'{c}={v:.8g}' for c, v in zip(sol.coordinates, sol.q[-1]))}")
    return lines



def balance_lines(sol) -> list[str]:
    """The energy balance of `sol` in one line where h is no first integral
    (`lagcomp.integrate.energy_balance.balance_or_none`); nothing otherwise."""
    from lagcomp.integrate.energy_balance import balance_or_none

    balance = balance_or_none(sol)
    if balance is None:
        return []
    works = ", ".join(f"{name} {values[-1]:.6g}" for name, values in balance.work.items() if values.any())
    line = (f"balance     {balance.quantity}: change {balance.change[-1]:.6g} = work ({works or 'none'}) "
            f"+ residual {balance.residual[-1]:.3g} (max relative {balance.relative_residual:.3g})")
    return [line]
