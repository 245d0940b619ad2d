"""The `lagcomp` command line: run, sweep, show, bench, analyse and animate a model; regenerate `generated/`.

    lagcomp list
    lagcomp show double_pendulum         (add --latex for the equations as LaTeX)
    lagcomp run double_pendulum --t-end 20 --method dop853 --param g=9.81 --out run.npz --plot run.png
    lagcomp run my_models.py:cart_pole --input F=push.csv --config run.toml --out run.csv
    lagcomp sweep simple_pendulum --grid theta=0.1:1.5:8 --out sweep.nc
    lagcomp bench double_pendulum        (kernel ns/call, op counts, steps/s per method, compile times)
    lagcomp stability hoop_bead --param Omega --range 1 8 --set epsilon=0 --q 3.14159265 --plot eig.png
    lagcomp animate double_pendulum -o double_pendulum.gif --t-end 10 --fps 15
    lagcomp generate generated/          (add --check to only report stale files)
    lagcomp precompile                   (compile every library driver now, not at its first use)
    lagcomp precompile NAME --all        (compile a model and build its on-demand kernels now)
    lagcomp precompile NAME --specialize dop853   (and its driver specialised for dop853: `specialize=True`)

The MODEL of every model command is a bundled example, a model compiled earlier under a name, or a System in
a file or module, by the rule `lagcomp.cli_support.models` states; each command prints which one it ran.
Inputs, parameters and initial state come from flags and ``--config`` (`lagcomp.cli_support.run_inputs`);
results go to the format their file's suffix names (`lagcomp.cli_support.outputs`).  docs/guide/cli.md has it all.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import warnings
from pathlib import Path

from lagcomp.cli_support.help import MODEL_HELP, examples_epilog, initial_state_flags
from lagcomp.cli_support.models import key_values, resolve
from lagcomp.cli_support.outputs import (
    check_plot_path,
    check_result_path,
    check_writable,
    write_solution,
    write_sweep,
)
from lagcomp.cli_support.reports import run_lines
from lagcomp.cli_support.run_inputs import check_inputs, run_values
from lagcomp.cli_support.trees import is_tree, refuse_tree, show_tree
from lagcomp.errors import LagcompError


def _model(args):
    """The model the command names (`lagcomp.cli_support.models`: the rule for names, files and modules), and
    its `ModelSource`; prints which model it is, and a note when a model of the user's shares its name."""
    source = resolve(args)
    model = source.model()
    _say_which(source, model)
    return source, model


def _say_which(source, model=None) -> None:
    print(f"model       {source.label}")
    note = None if model is None else source.note(model)
    if note:
        print(f"lagcomp: note: {note}", file=sys.stderr)


def cmd_list(args) -> int:
    from lagcomp import examples

    width = max(map(len, examples.EXAMPLES))
    for name, factory in examples.EXAMPLES.items():
        print(f"{name:<{width}}  {factory().description}")
    return 0


def _show_compiled(model) -> int:
    """`show` for a user's model from the cache: what the cache records, and the equations its module keeps."""
    print(f"{model.name}: {model.description or '(no description)'}   [compiled model from the cache]\n")
    print(f"coordinates q  = ({', '.join(model.coordinates)})")
    print(f"parameters  p  = ({', '.join(model.parameters)})   [kernel order]")
    print(f"defaults       = {model.defaults}")
    print(f"q0, qd0        = {model.q0}, {model.qd0}")
    print(f"cyclic         = {list(model.cyclic) or 'none'}")
    print(f"separable      = {model.separable} (explicit symplectic methods "
          f"{'apply' if model.separable else 'do not apply'})")
    if model.k:
        kinds = ", ".join(f"{c} ({'holonomic' if h else 'nonholonomic'})"
                          for c, h in zip(model.constraints, model.holonomic))
        print(f"constraints    = {kinds}")
    if model.events:
        print(f"events         = {', '.join(e.name for e in model.events)}")
    print(f"\n{model.equations()}")
    print(f"\noperations after CSE: {model.operations}")
    print(f"generated module: {model.source_path}")
    return 0


def cmd_show(args) -> int:
    source = resolve(args)
    if args.latex or source.system is None:  # from the module (`Model.equations`): no sympy where it is cached
        model = source.model()
        if args.latex:
            print(model.equations().latex)
            return 0
        _say_which(source, model)
        return _show_compiled(model)
    import sympy as sp

    from lagcomp.mechanics.lagrange import derive
    from lagcomp.runtime import Model, compile

    system = source.system()
    if isinstance(system, Model):
        _say_which(source, system)
        return _show_compiled(system)
    if is_tree(system):   # (its equations are its recursions: no derivation)
        model = compile(system, cache_dir=args.cache_dir)
        _say_which(source, model)
        return show_tree(system, model)
    eom = derive(system)
    model = compile(system, cache_dir=args.cache_dir, eom=eom)
    _say_which(source, model)
    print(f"{system.name}: {system.description}\n")
    print(f"coordinates q  = ({', '.join(system.coordinate_names)})")
    print(f"parameters  p  = ({', '.join(system.parameter_names)})   [kernel order]")
    print(f"defaults       = {system.defaults}")
    print(f"cyclic         = {list(eom.cyclic) or 'none'}")
    print(f"separable      = {eom.separable} (explicit symplectic methods {'apply' if eom.separable else 'do not apply'})\n")
    print("Equations of motion  M(q, t) q̈ = F(q, q̇, t):\n")
    print("M =")
    print(sp.pretty(eom.M, use_unicode=True))
    print("\nF =")
    print(sp.pretty(eom.F, use_unicode=True))
    if eom.k:
        kinds = ", ".join(f"{c} ({'holonomic' if h else 'nonholonomic'})" for c, h in zip(eom.constraint_names, eom.holonomic))
        print(f"\nconstraints Λ(q, t) q̇ + b = 0, multipliers λ in this order: {kinds}")
        print("M q̈ = F + Λᵀ λ,  Λ q̈ = γ\n\nΛ =")
        print(sp.pretty(eom.C, use_unicode=True))
        print("\nb =")
        print(sp.pretty(eom.b, use_unicode=True))
        print("\nγ =")
        print(sp.pretty(eom.gamma, use_unicode=True))
    print("\nenergy T + V =", eom.energy)
    print("energy function h =", eom.energy_function)
    print(f"\noperations after CSE: {model.operations}")
    print(f"generated module: {model.source_path}")
    return 0


def cmd_run(args) -> int:
    check_result_path(args.out, "--out")
    check_plot_path(args.plot, "--plot")
    values = run_values(args)
    started = time.perf_counter()
    _, model = _model(args)
    check_inputs(model, values.inputs)
    compiled = time.perf_counter()
    origin = "from cache" if model.from_cache else "derived and emitted"
    print(f"{model.name}: {origin} in {compiled - started:.2f} s ({model.source_path})", file=sys.stderr)
    options = dict(method=args.method, save_every=args.save_every, projection=args.projection,
                   project_initial=args.project_initial, record="summary" if args.summary else "trajectory",
                   progress=False if args.quiet else None)
    if args.baumgarte:
        options["baumgarte"] = tuple(args.baumgarte)
    from lagcomp.integrate.methods import get_method

    if not get_method(args.method).adaptive:  # fixed-step methods
        options["dt"] = args.dt if args.dt is not None else 1e-3
    else:
        options.update(rtol=args.rtol, atol=args.atol)
        if args.dt is not None:
            options["first_step"] = args.dt
    t_start = values.t_start if values.t_start is not None else 0.0
    t_end = values.t_end if values.t_end is not None else model.t_end
    run = dict(q0=values.q0, qd0=values.qd0, u0=values.u0, params=values.params,
               **({"inputs": values.inputs} if values.inputs else {}))
    warmed = _warm_up(model, t_start, t_end, run, options)
    print(f"numba: kernels and driver ready in {warmed:.2f} s (compiled on a first run, then loaded from its cache)",
          file=sys.stderr)
    begun = time.perf_counter()
    sol = model.simulate((t_start, t_end), **run, **options)
    elapsed = time.perf_counter() - begun
    if sol.projected_initial_state is not None:
        start = ", ".join(f"{v:.10g}" for v in sol.projected_initial_state)
        print(f"initial     projected onto the constraints: y0 = ({start})")
    print(f"method      {sol.method}   status {sol.status}: {sol.message}")
    print(f"time span   [{sol.t[0]:g}, {sol.t[-1]:g}]   steps {sol.nsteps}   rejected {sol.nrejected}   rhs evaluations {sol.nfev}"
          + (f"   Jacobians {sol.njev}   LU factorizations {sol.nlu}" if sol.njev else ""))
    print(f"wall time   {elapsed:.3f} s (integration; numba compilation or loading before it: {warmed:.2f} s)")
    for line in run_lines(sol, model):
        print(line)
    if args.out:
        print(f"saved       {write_solution(sol, args.out)} ({len(sol.t)} points)")
    if args.plot:
        from lagcomp.plots import plot_run

        try:
            plot_run(sol, title=f"{model.name}: {sol.method}, {len(sol.t)} points").savefig(args.plot, dpi=120)
        except ImportError as err:  # matplotlib is an optional extra
            raise LagcompError(str(err)) from err
        marked = any(len(r) and (r.impulses is not None or r.jumps) for r in sol.events.values())
        print(f"plotted     {args.plot} (coordinates and energy error vs time"
              f"{'; resets and impacts marked' if marked else ''})")
    return 0 if sol.success else 1


def cmd_animate(args) -> int:
    check_writable(args.output, "--output")
    import importlib.util

    from lagcomp.animation import (
        EXAMPLE_DRAWINGS,
        animate,
        body_drawing,
        check_format,
        frame_times,
    )

    check_format(args.output)
    if importlib.util.find_spec("matplotlib") is None:  # known before the run, not after it
        raise LagcompError("lagcomp animate needs matplotlib: pip install 'lagcomp[plots]'.")
    values = run_values(args)
    source, model = _model(args)
    check_inputs(model, values.inputs)
    family = re.sub(r"_\d+$", "", args.name) if args.name.startswith("n_link_pendulum") else args.name
    drawing = EXAMPLE_DRAWINGS.get(family) if source.kind == "example" else None
    if drawing is None and not getattr(model.kernels, "GEOMETRY", ()):
        raise LagcompError(f"lagcomp animate draws the bodies of a model built from lc.Particle / lc.RigidBody, and the "
                           f"pendulums {sorted(EXAMPLE_DRAWINGS)}; {model.name!r} has no bodies: build it from "
                           "bodies, or name the points to draw from Python: lagcomp.animate(sol, points={'bob': (x, y)}).")
    import numpy as np

    t_start = values.t_start if values.t_start is not None else 0.0
    t_end = values.t_end if values.t_end is not None else model.t_end
    times = frame_times(np.array([t_start, t_end]), args.fps, args.speed)
    sol = model.simulate((t_start, t_end), q0=values.q0, qd0=values.qd0, params=values.params,
                         **({"inputs": values.inputs} if values.inputs else {}),
                         t_eval=times, rtol=1e-10, atol=1e-10, progress=False)  # saved at the frames' times
    shown = drawing(model.coordinates) if drawing is not None else body_drawing(sol)
    animate(sol, **shown, fps=args.fps, speed=args.speed, title=model.name, save=args.output,
            progress=False if args.quiet else None)
    print(f"animated    {Path(args.output)}: {len(times)} frames of t in [{t_start:g}, {sol.t[-1]:g}] at "
          f"{args.fps:g} fps, speed {args.speed:g} ({sol.method}: {sol.message})")
    return 0 if sol.success else 1


def _warm_up(model, t0: float, t1: float, run: dict, options: dict) -> float:
    """Seconds numba takes to compile (or load from its cache) what a run with `options` calls.

    A run of one step (or a millionth of the span) with the same method and options: the timed run
    after it is integration only.  Bad options raise here, as they would in the run itself.
    """
    from lagcomp.integrate.status import Status

    started = time.perf_counter()
    span = options.get("dt") or options.get("first_step") or 1e-6 * (t1 - t0)
    sol = model.simulate((t0, t0 + min(span, t1 - t0)), **run, **{**options, "record": "summary"})
    if sol.status == Status.INTERRUPTED:  # Ctrl-C while numba compiled: stop here, not after the whole run
        raise KeyboardInterrupt
    return time.perf_counter() - started


def cmd_bench(args) -> int:
    """Kernel cost, op counts, steps/s of every applicable method and compile times of one model."""
    from lagcomp.benchmark import report

    values = run_values(args)
    started = time.perf_counter()
    source, model = _model(args)
    check_inputs(model, values.inputs)
    loaded = time.perf_counter() - started
    example = (args.name, key_values(args.arg, "--arg")) if source.kind == "example" else None  # the cold compile needs its name
    model.initial_state(values.q0, values.qd0)  # checked: a message, not a traceback
    model.parameter_vector(values.params, **({"inputs": values.inputs, "span": (0.0, model.t_end)}
                                             if values.inputs else {}))
    if values.q0 is not None:  # the values the benchmark runs from, for this process only
        model.q0 = tuple(values.q0)
    if values.qd0 is not None:
        model.qd0 = tuple(values.qd0)
    model.defaults.update(values.params)
    print(report(model, example=example, load_seconds=loaded, repeats=args.repeats, dt=args.dt, steps=args.steps,
                 methods=args.methods, cold=not args.no_cold, inputs=values.inputs or None), end="")
    return 0


def cmd_generate(args) -> int:
    from lagcomp.codegen.bundled import write_generated

    stale = write_generated(Path(args.directory), check=args.check)
    if args.check:
        for path in stale:
            print(f"stale: {path}")
        return 1 if stale else 0
    for path in stale:
        print(f"wrote {path}")
    return 0


def library_drivers() -> list[str]:
    """The library drivers and sweep loops (``"module:function"``), each once: those the method registry
    names, then the batched sweep loops (`lagcomp.integrate.sweep.BATCHED`) and a sweep's impulse loop."""
    from lagcomp.integrate.contacts import IMPULSES
    from lagcomp.integrate.methods import METHODS
    from lagcomp.integrate.sweep import BATCHED, TAYLOR_LANES_LOOP

    references = [ref for m in METHODS.values() for ref in (m.driver, m.sweep) if ref is not None]
    references += [ref for ref in BATCHED.values() if ":" in ref] + [TAYLOR_LANES_LOOP[0], IMPULSES]
    return list(dict.fromkeys(references))


def _precompile_shared_kernels() -> bool:
    """Compile the library kernels that drivers take in place of a model's own, for the kernel types the drivers
    take them as (numba caches each signature, return type included, apart): the hooks of models without
    constraints or events (`lagcomp.kernel_support.trivial`) and the ``event_reset`` of a model whose events
    reset nothing (`lagcomp.integrate.drivers.events.unchanged_state`).  Whether any was compiled (else loaded
    from numba's cache)."""
    from lagcomp.integrate.drivers import kernel_types
    from lagcomp.integrate.drivers.events import unchanged_state
    from lagcomp.kernel_support import trivial

    kernels = ((trivial.project, kernel_types.PROJECT), (trivial.constraint_residual, kernel_types.RESIDUAL),
               (trivial.event_values, kernel_types.EVENTS), (unchanged_state, kernel_types.EVENT_RESET))
    for kernel, kind in kernels:
        kernel.compile(kind.signature)
    return any(sum(kernel.stats.cache_misses.values()) for kernel, _ in kernels)


def cmd_precompile(args) -> int:
    """Compile every library driver into numba's cache now, so that no run pays for it later.

    Importing a driver module compiles its drivers from their explicit
    signatures, or loads them from numba's cache when an earlier process
    compiled them; one line per module says which, and how long it took.
    """
    from lagcomp.integrate.methods import library_function

    if args.name is not None:
        return _precompile_model(args)
    if args.specialize or args.specialize_sweep:
        raise LagcompError("--specialize compiles a model's specialised driver: name the model, e.g. "
                           "`lagcomp precompile double_pendulum --specialize dop853`.")
    modules: dict[str, list[str]] = {}
    for reference in library_drivers():
        module, _, _ = reference.partition(":")
        modules.setdefault(module, []).append(reference)
    started = time.perf_counter()
    for i, (module, references) in enumerate(modules.items(), 1):
        before = time.perf_counter()
        drivers = [library_function(reference) for reference in references]
        compiled = any(sum(driver.stats.cache_misses.values()) for driver in drivers)
        names = ", ".join(reference.partition(":")[2] for reference in references)
        how = "compiled" if compiled else "loaded from numba's cache"
        print(f"[{i}/{len(modules)}] {module} ({names}): {how} in {time.perf_counter() - before:.2f} s", flush=True)
    before = time.perf_counter()
    how = "compiled" if _precompile_shared_kernels() else "loaded from numba's cache"
    print(f"lagcomp.kernel_support.trivial and events.unchanged_state (kernels models share): {how} in "
          f"{time.perf_counter() - before:.2f} s", flush=True)
    print(f"{sum(map(len, modules.values()))} library drivers ready in {time.perf_counter() - started:.1f} s")
    return 0


def _precompile_model(args) -> int:
    """``lagcomp precompile MODEL [--all]``: compile the model MODEL names (the rule of every model command) into the cache, and with ``--all`` its on-demand kernels too (`lagcomp.codegen.kinds`), so that no
    later feature lowers anything (nor needs sympy); numba compiles each kernel at its first call."""
    _, model = _model(args)
    print(f"{model.name}: eager module {model.source_path}")
    if args.all:
        for kind, entry in model.on_demand_entries.items():
            print(f"{model.name}: on-demand kernels ({kind}) {entry.path}")
    for name in args.specialize:
        _specialise(model, name)
    for name in args.specialize_sweep:
        _specialise(model, name, sweep=True)
    return 0


def _specialise(model, name: str, sweep: bool = False) -> None:
    """``--specialize METHOD``: compile (or load) `model`'s driver specialised for the method `name`; with `sweep`
    (``--specialize-sweep``) its sweep loop."""
    from lagcomp.integrate import specialize
    from lagcomp.integrate.methods import get_method

    method = get_method(name)
    if method.name not in specialize.SPECIALISABLE:
        raise LagcompError(f"--specialize {name}: the specialised drivers cover {', '.join(specialize.SPECIALISABLE)}.")
    before = time.perf_counter()
    how = "compiled" if specialize.prepare(model, method, sweep) else "loaded from numba's cache"
    print(f"{model.name}: {method.name} {'sweep loop' if sweep else 'driver'} specialised, {how} in "
          f"{time.perf_counter() - before:.2f} s ({specialize.driver(model, method, sweep).__module__})")


def _grid_axis(spec: str, what: str) -> tuple[str, object]:
    """``name=LO:HI:N`` as (name, N evenly spaced values), or ``name=V`` as (name, float)."""
    name, sep, value = spec.partition("=")
    if not sep or not name:
        raise LagcompError(f"{what} {spec!r} must look like name=value or name=LO:HI:N.")
    parts = value.split(":")
    try:
        if len(parts) == 1:
            return name, float(value)
        if len(parts) == 3:
            lo, hi, count = float(parts[0]), float(parts[1]), int(parts[2])
            if count >= 1:
                import numpy as np

                return name, np.linspace(lo, hi, count)
    except ValueError:
        pass
    raise LagcompError(f"{what} {spec!r}: expected a number, or LO:HI:N with N a whole number >= 1.")


def _sweep_outputs(specs: list[str], adaptive: bool, t_span) -> tuple[tuple, dict]:
    """`--output` values as (Model.sweep outputs, extra options): final, every=K, times=N, max-energy-error, events."""
    import numpy as np

    outputs, options = [], {}
    for spec in specs or ["final"]:
        key, _, value = spec.partition("=")
        if key == "final":
            continue
        if key in ("max-energy-error", "events"):
            outputs.append("energy" if key == "max-energy-error" else "events")
            continue
        if key in ("every", "times"):
            try:
                count = int(value)
            except ValueError:
                count = 0
            if count < 1:
                raise LagcompError(f"--output {spec!r}: {key}=K needs a whole number K >= 1.")
            if key == "every" and adaptive:
                raise LagcompError("--output every=K saves every K-th step of a fixed-step method; "
                                   "an adaptive one saves at common times: --output times=N.")
            if key == "times" and not adaptive:
                raise LagcompError("--output times=N is for adaptive methods; fixed-step ones save every K-th "
                                   "step: --output every=K.")
            outputs.append("dense")
            if key == "every":
                options["save_every"] = count
            else:
                options["t_eval"] = np.linspace(*t_span, count)
            continue
        raise LagcompError(f"--output {spec!r}: choose final, every=K, times=N, max-energy-error or events.")
    return tuple(dict.fromkeys(outputs)), options


def cmd_sweep(args) -> int:
    import numpy as np

    from lagcomp.integrate.methods import get_method
    from lagcomp.integrate.sweep import NOT_RUN

    check_result_path(args.out, "--out")
    values = run_values(args, params_flag=None)  # --param may sweep: read below
    _, model = _model(args)
    check_inputs(model, values.inputs)
    method = get_method(args.method)
    t_span = (values.t_start if values.t_start is not None else 0.0,
              values.t_end if values.t_end is not None else model.t_end)
    grid, params = {}, dict(values.params)  # axes in order: the --grid ones, then the swept --param ones
    for spec in (args.grid or []):
        name, value = _grid_axis(spec, "--grid")
        grid[name] = np.atleast_1d(value)
    for spec in (args.param or []):
        name, value = _grid_axis(spec, "--param")
        (params if isinstance(value, float) else grid)[name] = value
    for name in grid:  # a swept name wins over its value in --config
        params.pop(name, None)
    if not grid:
        raise LagcompError("Nothing to sweep: give at least one --grid NAME=LO:HI:N (a coordinate, "
                           "<coordinate>_dot or a parameter) or --param NAME=LO:HI:N.")
    outputs, options = _sweep_outputs(args.output, method.adaptive, t_span)
    if method.adaptive:
        options.update(rtol=args.rtol, atol=args.atol)
    else:
        options["dt"] = args.dt if args.dt is not None else 1e-3
    if args.projection is not None:
        options["projection"] = args.projection
    client = None
    if args.scheduler:
        try:
            from dask.distributed import Client
        except ImportError as err:
            raise LagcompError("--scheduler needs dask.distributed: pip install 'lagcomp[dask]'.") from err
        client = Client(args.scheduler)
    started = time.perf_counter()
    if values.inputs:
        options["inputs"] = values.inputs
    sweep = model.sweep(t_span, grid, combine=args.combine, q0=values.q0, qd0=values.qd0, params=params,
                        method=method.name, output=outputs, workers=args.workers, client=client,
                        batched=args.batched, project_initial=args.project_initial,
                        progress=False if args.quiet else None, **options)
    elapsed = time.perf_counter() - started
    count, done = int(np.prod(sweep.shape)), int(sweep.done.sum())
    axes = ", ".join(f"{name} ({len(sweep.axes[name])} values)" for name in sweep.names)
    print(f"sweep       {model.name}: {count} trajectories over {axes}, {sweep.combine}")
    if done < count:
        print(f"interrupted {done} of {count} trajectories done (the others have status {NOT_RUN}, `done` False)")
    print(f"method      {sweep.method}   t in [{t_span[0]:g}, {t_span[1]:g}]   {int(sweep.nsteps.sum())} steps in all")
    print(f"wall time   {elapsed:.3f} s ({done / elapsed:,.0f} trajectories/s over the {done} done)")
    statuses, counts = np.unique(sweep.status[sweep.done], return_counts=True)
    print("status      " + ", ".join(f"{int(s)}: {int(c)}" for s, c in zip(statuses, counts)))
    if sweep.energy_error is not None:
        finite = sweep.energy_error[np.isfinite(sweep.energy_error)]
        if finite.size:
            what = "energy balance residual (h − h(0) − ∫P dt)" if sweep.energy_balance else "relative error of T + V"
            print(f"energy      largest {what} per trajectory: median {np.median(finite):.3g}, "
                  f"max {finite.max():.3g}")
    from lagcomp.event_report import sweep_event_summary

    for name, record in (sweep.events or {}).items():
        print(f"event       {name}: {int(record['count'].sum())} occurrence(s) in all"
              f"{sweep_event_summary(record, model.contacts)}")
    if args.out:
        written = write_sweep(sweep, args.out)
        dense = " (final states; the saved time series are in .npz and .nc files)" \
            if written.suffix.lower() == ".csv" and sweep.dense is not None else ""
        print(f"saved       {written}{dense}")
    if client is not None:
        client.close()
    return 0 if sweep.done.all() else 130


def cmd_stability(args) -> int:
    """Eigenvalues of a steady motion of a model along a parameter or speed, and where stability changes."""
    import numpy as np

    from lagcomp.analysis import stability_sweep

    check_plot_path(args.plot, "--plot")
    run = run_values(args, params_flag="set")
    source = resolve(args)
    if source.system is None:
        raise LagcompError(f"lagcomp stability linearizes the symbolic System, which a compiled model does not keep: "
                           f"give the file that defines {args.name!r} (path/to/model.py:NAME) or its module.")
    system = source.system()
    if is_tree(system):
        refuse_tree(system, "stability", "it linearizes a steady motion from a System's T and V; "
                    "lagcomp.analysis.linearize(model, q) linearizes a tree's model about an equilibrium.")
    _say_which(source)
    held = _held_inputs(system, run.inputs)
    q = args.q if args.q is not None else run.q0 if run.q0 is not None else system.q0
    u = [0.0] * len(system.coordinates) if args.u is None else args.u
    values = np.linspace(args.range[0], args.range[1], args.num)
    sweep = stability_sweep(system, args.param, values, q, u, run.params, drop=args.drop or (), inputs=held)
    print(f"{system.name}: eigenvalues of the linearization about q = {list(q)}, u = {list(u)} "
          f"in the reduced state ({', '.join(sweep.states)})")
    for value, unstable, row in zip(sweep.values, sweep.unstable, sweep.eigenvalues):
        shown = "  ".join(f"{z.real:+.6g}{z.imag:+.6g}j" if z.imag else f"{z.real:+.6g}" for z in row)
        print(f"{args.param} = {value:<10.6g} {'unstable' if unstable else 'stable  '}  {shown}")
    for change in sweep.changes:
        print(f"becomes {change.becomes} at {args.param} = {change.value:.12g} ({change.crossing} crossing)")
    if not sweep.changes:
        print(f"no change of stability for {args.param} in [{values[0]:g}, {values[-1]:g}]")
    if args.plot:
        from lagcomp.plots import plot_stability

        plot_stability(sweep, title=f"{system.name}: eigenvalues vs {args.param}").savefig(args.plot, dpi=120)
        print(f"plot: {args.plot}")
    return 0


def _held_inputs(system, inputs: dict) -> dict | None:
    """The constant each run-time input of `system` is held at while `lagcomp stability` linearizes (``--input
    NAME=2.5``): a steady motion needs them constant, so a table or a function is refused, as is a missing one."""
    names = list(system.input_names)
    if not names:
        return None
    varying = [name for name in names if not isinstance(inputs.get(name), float)]
    if varying:
        raise LagcompError(f"lagcomp stability linearizes about a steady motion, with each run-time input held at a "
                           f"constant; {system.name!r} reads {', '.join(names)}: give "
                           f"{' '.join(f'--input {name}=VALUE' for name in varying)} (a number; a table or a "
                           "function varies with time).")
    return {name: inputs[name] for name in names}


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lagcomp", description="Compile and simulate Lagrangian systems.")
    parser.add_argument("--cache-dir", help="cache root (default: $LAGCOMP_CACHE_DIR or the user cache directory)")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="list the bundled examples").set_defaults(func=cmd_list)

    from lagcomp.integrate.methods import METHODS

    def model_command(name, help_, *, inputs=True):
        p = sub.add_parser(name, help=help_, description=help_, epilog=examples_epilog(name),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        p.add_argument("name", metavar="MODEL", help=MODEL_HELP)
        p.add_argument("--arg", action="append", metavar="K=V",
                       help="argument of the example's factory, or of the function MODEL names, e.g. n=5")
        p.add_argument("--cached", action="store_true",
                       help="MODEL is the model compiled earlier under that name (lagcomp.load), even when a "
                            "bundled example has the name")
        p.add_argument("--config", metavar="FILE",
                       help="parameters, initial state, inputs and time span from a .toml or .json file (keys "
                            "params, inputs, q0, qd0, u0, t_start, t_end); flags given as well win")
        if inputs:
            p.add_argument("--input", action="append", metavar="NAME=SIGNAL",
                           help="an input of the model (lagcomp.Input): NAME=2.5 (constant), NAME=table.csv "
                                "(columns time,value), NAME=table.csv:COLUMN, NAME=...@linear (straight segments), "
                                "NAME=file.py:FUNCTION (a numba function u(t, y, p))")
        return p

    show = model_command("show", "print the derived equations (of a model compiled earlier, what the cache "
                                 "records) and the generated module's path", inputs=False)
    show.add_argument("--latex", action="store_true",
                      help="print only the equations of motion, constraints and energy as LaTeX (an align* "
                           "environment; model.equations() in Python)")
    show.set_defaults(func=cmd_show)
    run = model_command("run", "simulate a model and print a summary")
    run.add_argument("--t-start", type=float, help="start time (default 0)")
    run.add_argument("--t-end", type=float, help="end time (default: the model's)")
    run.add_argument("--method", default="dop853", choices=list(METHODS))
    run.add_argument("--dt", type=float, help="step of fixed-step methods (default 1e-3); first step of adaptive ones")
    run.add_argument("--rtol", type=float, default=1e-10)
    run.add_argument("--atol", type=float, default=1e-10)
    run.add_argument("--save-every", type=int, default=1, metavar="K")
    initial_state_flags(run)
    run.add_argument("--u0", type=float, nargs="+",
                     help="initial speeds u (a model compiled from a KanesMethod, state (q, u): one per speed, "
                          "in its order `speeds`; such a model refuses --qd0)")
    run.add_argument("--out", metavar="FILE", help="write the solution; the suffix names the format: .npz (every "
                                                   "array), .csv (t, state, energy, reactions), .nc (netCDF, xarray)")
    run.add_argument("--plot", metavar="IMAGE", help="draw coordinates and energy error vs time to this image, "
                                                     "format by suffix: .png, .pdf, .svg, ... (needs matplotlib)")
    run.add_argument("--summary", action="store_true",
                     help="keep only the first and last states and running reductions (O(1) memory for long runs)")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--projection", action=argparse.BooleanOptionalAction, default=None,
                     help="project onto the constraints after every step (default: on for rk4)")
    run.add_argument("--baumgarte", type=float, nargs=2, metavar=("ALPHA", "BETA"), help="Baumgarte gains")
    run.add_argument("--project-initial", action="store_true",
                     help="project inconsistent initial conditions onto the constraints")
    run.set_defaults(func=cmd_run)
    sweep = model_command("sweep", "integrate a grid of initial values and parameters on every core")
    sweep.add_argument("--grid", "--q0-grid", action="append", metavar="NAME=LO:HI:N",
                       help="swept initial value or parameter, N evenly spaced values (coordinate, "
                            "<coordinate>_dot or parameter name)")
    sweep.add_argument("--param", action="append", metavar="NAME=V|NAME=LO:HI:N",
                       help="parameter value, or a swept range")
    sweep.add_argument("--combine", choices=["product", "zip"], default="product",
                       help="Cartesian product of the axes (default) or element-wise")
    sweep.add_argument("--output", action="append", metavar="KIND",
                       help="final (default), every=K (fixed-step), times=N (adaptive), max-energy-error, events")
    sweep.add_argument("--t-start", type=float, help="start time (default 0)")
    sweep.add_argument("--t-end", type=float, help="end time (default: the model's)")
    sweep.add_argument("--method", default="dop853", choices=sorted(METHODS))
    sweep.add_argument("--dt", type=float, help="step of fixed-step methods (default 1e-3)")
    sweep.add_argument("--rtol", type=float, default=1e-10)
    sweep.add_argument("--atol", type=float, default=1e-10)
    sweep.add_argument("--q0", type=float, nargs="+", help="initial coordinates not swept")
    sweep.add_argument("--qd0", type=float, nargs="+", help="initial velocities not swept")
    sweep.add_argument("--workers", type=int, help="threads (default: one per CPU)")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="run the chunks on this Dask scheduler")
    sweep.add_argument("--batched", action="store_true", help="SIMD lanes (rk4, dop853, taylor; final states and energy)")
    sweep.add_argument("--projection", action=argparse.BooleanOptionalAction, default=None,
                       help="project onto the constraints after every step (default: on for fixed-step methods)")
    sweep.add_argument("--project-initial", action="store_true",
                       help="project inconsistent initial states onto the constraints")
    sweep.add_argument("--out", metavar="FILE", help="write the sweep; the suffix names the format: .npz (every "
                                                     "array), .csv (one row per trajectory), .nc (netCDF, xarray)")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(func=cmd_sweep)
    bench = model_command("bench", "time one model: kernel ns/call, op counts, steps/s per method, compile times")
    bench.set_defaults(func=cmd_bench)
    bench.add_argument("--repeats", type=int, default=5, help="timed repeats per figure (medians)")
    bench.add_argument("--dt", type=float, default=1e-3, help="step of the fixed-step methods")
    bench.add_argument("--steps", type=int, default=100_000, help="steps of each fixed-step run")
    bench.add_argument("--methods", nargs="+", metavar="METHOD", help="time only these methods (default: all that apply)")
    bench.add_argument("--no-cold", action="store_true", help="skip the cold compile in a fresh process (bundled "
                                                              "examples only)")
    initial_state_flags(bench)
    stability = model_command("stability", "eigenvalues of a steady motion along a parameter; where stability "
                                           "changes (needs the System: a bundled example, a file or a module; "
                                           "each input held at a constant, --input NAME=VALUE)")
    stability.add_argument("--param", required=True, help="swept parameter, or speed (<coordinate>_dot)")
    stability.add_argument("--range", type=float, nargs=2, required=True, metavar=("LO", "HI"))
    stability.add_argument("--num", type=int, default=41, help="values in the range (default 41)")
    stability.add_argument("--set", action="append", metavar="K=V", help="value of another parameter, e.g. g=9.81")
    stability.add_argument("--q", type=float, nargs="+",
                           help="coordinates of the steady motion (default: --config's q0, else the model's q0)")
    stability.add_argument("--u", type=float, nargs="+", help="its speeds (default: zero but the swept one; dependent ones completed)")
    stability.add_argument("--drop", nargs="+", metavar="NAME", help="ignorable coordinates/speeds to leave out")
    stability.add_argument("--plot", metavar="IMAGE", help="draw the eigenvalues vs the parameter, format by suffix "
                                                           "(needs matplotlib)")
    stability.set_defaults(func=cmd_stability)
    anim = model_command("animate", "draw a run as a GIF, MP4 or HTML player: the bodies of a model built from "
                                    "lc.Particle / lc.RigidBody, or a bundled pendulum (needs matplotlib)")
    anim.add_argument("-o", "--output", required=True, help="file to write: .gif, .mp4 (ffmpeg) or .html")
    anim.add_argument("--t-start", type=float, help="start time (default 0)")
    anim.add_argument("--t-end", type=float, help="end time (default: the model's)")
    anim.add_argument("--fps", type=float, default=30.0, help="frames per second of the clip (default 30)")
    anim.add_argument("--speed", type=float, default=1.0,
                      help="simulated seconds per second of clip (default 1; larger plays a long run faster)")
    anim.add_argument("--quiet", action="store_true", help="no progress bar while the frames are drawn")
    initial_state_flags(anim)
    anim.set_defaults(func=cmd_animate)
    gen = sub.add_parser("generate", help="regenerate the emitted modules of the bundled examples")
    gen.add_argument("directory", nargs="?", default="generated")
    gen.add_argument("--check", action="store_true", help="only list stale files; exit 1 if any")
    gen.set_defaults(func=cmd_generate)
    pre = sub.add_parser("precompile", help="compile every library integration driver now (once per "
                                            "installation) instead of at its first use; or, given a model, "
                                            "that model (--all: its on-demand kernels too)")
    pre.add_argument("name", nargs="?", metavar="MODEL", help=MODEL_HELP + " (default: the library drivers)")
    pre.add_argument("--cached", action="store_true", help="MODEL is the model compiled earlier under that name")
    pre.add_argument("--arg", action="append", metavar="K=V", help="argument of the example factory, e.g. n=5")
    pre.add_argument("--all", action="store_true", help="build the model's on-demand kernels now as well")
    pre.add_argument("--specialize", action="append", metavar="METHOD", default=[],
                     help="compile the model's driver specialised for METHOD (its kernels compile-time callees of "
                          "the driver, cached with the model) for runs with `specialize=True`; repeat for more methods")
    pre.add_argument("--specialize-sweep", action="append", metavar="METHOD", default=[],
                     help="compile the model's sweep loop specialised for METHOD, which sweeps of 10,000 trajectories "
                          "or more then run (`lagcomp.integrate.sweep`); repeat for more methods")
    pre.set_defaults(func=cmd_precompile)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings (a cache entry rebuilt, a cache directory replaced) as one line, without source lines."""
    print(f"lagcomp: warning: {message}", file=sys.stderr if file is None else file)


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return args.func(args)
    except LagcompError as err:
        print(f"lagcomp: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # runs and sweeps stop cleanly on their own; this is derivation or compilation
        print("lagcomp: interrupted (Ctrl-C); the cache is intact: its files are written whole or not at all, "
              "so the next command starts the interrupted work again.", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
