#!/usr/bin/python3
"""Turns the benchmark CSV files into the charts and the results table (docs/design.md §8).

Usage: plot.py DATA_DIR DOCS_DIR [PAGE]
       plot.py --fixes DATA_DIR DOCS_DIR   (only the late fixes' chart, DOCS_DIR/fixes.png)
       plot.py --ahrs DATA_DIR DOCS_DIR    (only the chart against Madgwick, DOCS_DIR/ahrs.png)

Reads DATA_DIR/sweep.csv, stability.csv, invariants.csv, step_costs.json and, when present,
node_bench.csv, real_streams.csv, fixes.csv and ahrs.csv; writes DOCS_DIR/*.png and
DOCS_DIR/results.md, and, given PAGE (docs/benchmarks.md), replaces the text between its
`<!-- >>> results -->` and `<!-- <<< results -->` markers, with the charts' paths relative to
PAGE's folder.

Runs with Debian's /usr/bin/python3 and python3-matplotlib; no other dependency.
"""
import csv
import json
import math
import os
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

KINEMATIC_SCENES = ["constant_rate", "coning", "fast_spin"]
DYNAMIC_SCENES = ["free_body", "dzhanibekov", "symmetric_top", "torqued"]
SCENES = KINEMATIC_SCENES + DYNAMIC_SCENES
TOLERANCES = [1e-6, 1e-9, 1e-12]
FLOOR = 1e-16  # zero errors are drawn here on log axes

# One colour and marker per method, the same in every chart. Each kind of method takes the next
# free style of its own list in the order the methods first appear in the sweep (the core's table
# order): kinematic methods from KINEMATIC_STYLES, the dynamic ones from DYNAMIC_STYLES, so a new
# method gets the next free style of its kind without an edit here and no other method's style
# moves (test/checks/integrator_lists.sh checks that one is free, and that evaluate_bag's
# kinematic colours are these). A method of both models (rk4: order 2 from rate samples in the
# kinematic model, the classical order 4 in the dynamic one) is two methods to a reader: its
# dynamic use takes the next of BOTH_MODELS_STYLES, and the charts and the text name it per
# model.
KINEMATIC_STYLES = [("tab:red", "v"), ("tab:blue", "o"), ("tab:orange", "s"), ("tab:olive", "D"),
                    ("tab:green", "^"), ("tab:gray", "p"), ("navy", "h")]
DYNAMIC_STYLES = [("tab:purple", "s"), ("tab:brown", "D"), ("tab:pink", "^"), ("black", "*"),
                  ("tab:cyan", "P"), ("lime", "<"), ("teal", ">")]
BOTH_MODELS_STYLES = [("darkgoldenrod", "X")]
STYLE = {}
BOTH_MODELS = set()  # methods the sweep runs in the kinematic and in the dynamic model


def model_of(scene):
    return "kinematic" if scene in KINEMATIC_SCENES else "dynamic"


def name(method, model=None):
    """A method as the charts name it: `kinematic rk4` and `dynamic rk4` are different methods
    behind one setting."""
    return f"{model} {method}" if model and method in BOTH_MODELS else method


def called(method, model=None):
    """A method as the text names it: the setting in code, the model in words."""
    return f"{model} `{method}`" if model and method in BOTH_MODELS else f"`{method}`"


def assign_styles(sweep, invariants):
    """Gives every method in the rows its style, in order of first appearance, then one to the
    dynamic use of each method of both models."""
    models = defaultdict(set)
    for r in sweep:
        models[r["method"]].add(model_of(r["scene"]))
    for r in invariants:
        models[r["method"]].add("dynamic")
    BOTH_MODELS.update(m for m, found in models.items() if len(found) > 1)
    for method, found in models.items():
        style(method, "kinematic" if "kinematic" in found else "dynamic")
    for method in models:
        style(method, "dynamic")


FAILURE_MARKERS = {
    "wrong_side": ("X", "wrong side of the separatrix"),
    "norm_lost": ("P", "norm lost (| |q| - 1 | > 0.1 in a step)"),
    "diverged": ("h", "diverged (error > 1 rad or energy changed > 100 %)"),
    "nonfinite": ("$\\infty$", "non-finite"),
}


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(row, key):
    value = row.get(key, "")
    return float(value) if value not in ("", None) else float("nan")


def style(method, model=None):
    key = name(method, model)
    if key not in STYLE:
        styles = (KINEMATIC_STYLES if model == "kinematic" else
                  BOTH_MODELS_STYLES if method in BOTH_MODELS else DYNAMIC_STYLES)
        taken = sum(1 for s in STYLE.values() if s in styles)
        STYLE[key] = styles[taken % len(styles)]
    return STYLE[key]


def floored(values):
    return [v if v > FLOOR else FLOOR for v in values]


def by_method(rows):
    groups = defaultdict(list)
    for r in rows:
        groups[r["method"]].append(r)
    return groups


def work(row):
    """ns per simulated second: the cost of following one second of motion."""
    return num(row, "ns_per_step") / num(row, "dt")


def method_label(method, rows, model=None):
    label = name(method, model)
    return label + " (auto)" if any(r["auto"] == "1" for r in rows) else label


# A line that sits on one drawn before it in the same panel (every error within this factor
# of the other method's at the same step, e.g. exp on euler for coning) is drawn dashed on top
# with hollow, larger markers, so the line below shows through, and its label names that line.
OVERLAP = 1.25


def overlaps(rows, drawn, x_key="dt", y_key="err_rad"):
    """The label of an earlier line in `drawn` ((label, rows) pairs) whose errors `rows` sit on
    at every common step, or None."""
    mine = {num(r, x_key): num(r, y_key) for r in rows}
    for label, other in drawn:
        theirs = {num(r, x_key): num(r, y_key) for r in other}
        common = [x for x in mine if x in theirs]
        if common and all(max(mine[x], FLOOR) <= OVERLAP * max(theirs[x], FLOOR) and
                          max(theirs[x], FLOOR) <= OVERLAP * max(mine[x], FLOOR)
                          for x in common):
            return label
    return None


def plot_line(ax, method, rows, xs, ys, model, under=None, note="", rank=0, thin=False):
    """One method's line, the `rank`-th drawn in its panel: its markers shrink with the rank, so
    a later marker on the same point sits inside the earlier ones; `auto`'s pick thick with
    large hollow markers (unless `thin`), a line that sits on `under` dashed and hollow on top
    of it."""
    colour, marker = style(method, model)
    is_auto = any(r["auto"] == "1" for r in rows) and not thin
    label = method_label(method, rows, model) + note + (f", on {under}" if under else "")
    if is_auto or under:
        marks = dict(markersize=11 if is_auto else max(12.0 - 1.6 * rank, 7.0),
                     markerfacecolor="none", markeredgecolor=colour, markeredgewidth=2.0)
    else:
        marks = dict(markersize=max(12.0 - (2.0 if thin else 1.6) * rank, 4.5),
                     markeredgecolor="white" if rank else colour, markeredgewidth=0.6)
    ax.plot(xs, floored(ys), color=colour, marker=marker, linewidth=3.0 if is_auto else 1.3,
            linestyle=(0, (4, 3)) if under else "-", label=label,
            zorder=5 if under else (3 if is_auto else 2), **marks)
    return name(method, model)


def work_precision_chart(sweep, path, advice):
    fig, axes = plt.subplots(2, 4, figsize=(20, 10))
    for ax, scene in zip(axes.flat, SCENES):
        rows = [r for r in sweep if r["scene"] == scene]
        drawn = []
        for method, group in by_method(rows).items():
            key = "tolerance" if is_tolerance_sweep(group) else "dt"
            group.sort(key=lambda r: -num(r, key))
            label = plot_line(ax, method, group, [work(r) for r in group],
                              [num(r, "err_rad") for r in group], model_of(scene),
                              overlaps(group, drawn), rank=len(drawn))
            drawn.append((label, group))
        kind = "kinematic, from rate samples" if scene in KINEMATIC_SCENES else "dynamic"
        ax.set_title(f"{scene} ({kind})")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("cost [ns per simulated second]")
        ax.set_ylabel("largest attitude error along the path [rad]")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    notes = axes.flat[-1]
    notes.axis("off")
    notes.text(0.0, 0.97, WORK_PRECISION_NOTE + both_models_note(sweep), va="top", fontsize=10,
               wrap=True)
    fig.suptitle("Work-precision: attitude error against cost, one line per method\n"
                 "Keep `auto` (thick line)" + (f": {advice}." if advice else "."), fontsize=14)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def model_orders(sweep, method):
    """(model, the median over the model's scenes of `method`'s measured order) pairs."""
    out = []
    for model, scenes in [("kinematic", KINEMATIC_SCENES), ("dynamic", DYNAMIC_SCENES)]:
        orders = [measured_order([r for r in sweep if r["scene"] == s and r["method"] == method])
                  for s in scenes]
        orders = [p for p in orders if p is not None and p >= 0.5]
        if orders:
            out.append((model, statistics.median(orders)))
    return out


def both_models_note(sweep):
    """What the notes say of each method that runs in both models."""
    lines = []
    for method in sorted(BOTH_MODELS):
        orders = ", ".join(f"{model} {method} order {p:.1f}"
                           for model, p in model_orders(sweep, method))
        lines.append(f"\n\n`integrator: {method}` runs two methods: the\n"
                     "kinematic one steps between rate samples\n"
                     "(the midpoint rate interpolated), the dynamic\n"
                     "one the equations of motion (docs/numerics.md\n"
                     f"§2, §5). Measured here:\n{orders}.")
    return "".join(lines)


WORK_PRECISION_NOTE = (
    "How to read: lower left is better.\n"
    "Each point is one step size (dopri5: one tolerance,\n"
    "at a 0.01 s output step).\n\n"
    "x: median CPU time per step / step size,\n"
    "   measured in the same run for all methods.\n"
    "y: largest rotation angle to the truth along the\n"
    "   whole path (closed form, exact torque-free\n"
    "   solution, or long-double Bulirsch-Stoer at 1e-16).\n\n"
    "Kinematic scenes: rates sampled at 1/dt and fed\n"
    "through KinematicPropagator::addSample.\n"
    "Errors at 1e-16 are exact to round-off.")


def is_tolerance_sweep(rows):
    """A method swept over its tolerance (dopri5) rather than over the step."""
    return any(r.get("tolerance") not in ("", None) for r in rows)


def measured_order(rows):
    """Median slope of log(error) against log(step) between neighbouring steps whose errors
    stay well above round-off (1e-10), or None."""
    points = sorted((num(r, "dt"), num(r, "err_rad")) for r in rows
                    if r["status"] == "ok" and num(r, "err_rad") > 1e-10)
    slopes = [math.log(e2 / e1) / math.log(h2 / h1)
              for (h1, e1), (h2, e2) in zip(points, points[1:])]
    return statistics.median(slopes) if slopes else None


def order_chart(sweep, path):
    panels = [("coning", "kinematic methods on the coning motion"),
              ("free_body", "dynamic methods on the free body (HLW)"),
              ("torqued", "dynamic methods with torque")]
    fig, axes = plt.subplots(1, 3, figsize=(18, 5.5))
    for ax, (scene, title) in zip(axes, panels):
        rows = [r for r in sweep if r["scene"] == scene]
        groups = {m: g for m, g in by_method(rows).items() if not is_tolerance_sweep(g)}
        rows = [r for g in groups.values() for r in g]
        drawn = []
        for method, group in groups.items():
            group.sort(key=lambda r: num(r, "dt"))
            p = measured_order(group)
            label = plot_line(ax, method, group, [num(r, "dt") for r in group],
                              [num(r, "err_rad") for r in group], model_of(scene),
                              overlaps(group, drawn),
                              f", order {p:.1f}" if p is not None and p >= 0.5 else "",
                              rank=len(drawn))
            drawn.append((label, group))
        # Reference slopes: the orders the methods of the panel show, rounded.
        orders = {round(p) for p in map(measured_order, groups.values()) if p and p >= 0.5}
        add_slopes(ax, rows, sorted(orders))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("step dt [s]")
        ax.set_ylabel("largest attitude error along the path [rad]")
        ax.set_title(title)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    fig.suptitle("Order of convergence: error against step, each method's measured order in its "
                 "label; dotted lines: reference slopes h^p")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def add_slopes(ax, rows, slopes):
    dts = sorted({num(r, "dt") for r in rows})
    if not dts:
        return
    lo, hi = dts[0], dts[-1]
    anchor = 1e-2
    for p in slopes:
        xs = [lo, hi]
        ys = [anchor * (x / hi) ** p for x in xs]
        ax.plot(xs, ys, "k:", linewidth=1.0, alpha=0.7)
        ax.text(lo, ys[0], f"h^{p} ", fontsize=10, va="center", ha="right")


def invariants_chart(rows, path):
    fig, axes = plt.subplots(1, 2, figsize=(15, 5.5))
    groups = by_method(rows)
    for ax, key, label in [(axes[0], "energy_rel_drift", "|E - E0| / E0"),
                           (axes[1], "momentum_rel_drift", "||M| - |M0|| / |M0|")]:
        for method, group in groups.items():
            colour, marker = style(method, "dynamic")
            tolerance = group[0].get("tolerance")
            line = name(method, "dynamic") + (f" (tol {tolerance})" if tolerance else "")
            ax.plot([num(r, "t") for r in group], floored(running_max([num(r, key)
                                                                        for r in group])),
                    color=colour, marker=marker, markevery=0.1, markersize=6, label=line,
                    linewidth=1.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"largest relative drift {label} up to t")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=9, loc="upper left")
    h = rows[0]["dt"] if rows else "?"
    axes[0].set_title(f"energy, free body (HLW), step {h} s")
    axes[1].set_title(f"|angular momentum|, free body (HLW), step {h} s")
    fig.suptitle("Invariants over a long run (1e-16: kept to round-off)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def running_max(values):
    out, worst = [], 0.0
    for v in values:
        worst = max(worst, v)
        out.append(worst)
    return out


def jitter_of(row):
    """Receipt latency's spread of a stability row (s: the exponential latency's mean and standard
    deviation); rows written before the column existed had none."""
    value = num(row, "jitter_s")
    return 0.0 if math.isnan(value) else value


def jitter_label(jitter):
    return ("exact stamps" if jitter == 0.0 else
            f"stamps late by an exponential latency of {jitter * 1e3:g} ms")


def stability_panel(ax, group_rows, title):
    drawn = []
    for method, group in by_method(group_rows).items():
        group.sort(key=lambda r: num(r, "omega_dt"))
        model = model_of(group[0]["scene"])
        colour, _ = style(method, model)
        xs = [num(r, "omega_dt") for r in group]
        ys = [min(num(r, "final_err_rad"), math.pi) if r["status"] != "nonfinite"
              else math.pi for r in group]
        label = plot_line(ax, method, group, xs, ys, model,
                          overlaps(group, drawn, "omega_dt", "final_err_rad"),
                          rank=len(drawn), thin=True)
        drawn.append((label, group))
        for x, y, r in zip(xs, floored(ys), group):
            if r["status"] in FAILURE_MARKERS:
                ax.plot([x], [y], linestyle="none", marker=FAILURE_MARKERS[r["status"]][0],
                        markersize=11, color=colour, markeredgecolor="black", zorder=4)
    ax.axhline(math.pi, color="gray", linewidth=0.8, linestyle=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("|Omega| dt [rad per step]")
    ax.set_ylabel("attitude error after the fixed time [rad]")
    ends = sorted(num(r, "dt") * num(r, "steps") for r in group_rows)
    ax.set_title(f"{title}: error after {ends[len(ends) // 2]:.0f} s", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")


def stability_chart(rows, path):
    """Kinematic scene: one panel per receipt jitter (top row); dynamic scenes below."""
    kinematic = [r for r in rows if r["scene"] == "fast_spin"]
    jitters = sorted({jitter_of(r) for r in kinematic})
    panels = [(f"fast_spin, {jitter_label(j)}", [r for r in kinematic if jitter_of(r) == j])
              for j in jitters]
    panels += [(scene, [r for r in rows if r["scene"] == scene])
               for scene in ["free_body", "dzhanibekov"] if any(r["scene"] == scene for r in rows)]
    columns = max(len(jitters), 1)
    lines = -(-len(panels) // columns)
    fig, axes = plt.subplots(lines, columns, figsize=(6.5 * columns, 5.5 * lines), squeeze=False)
    for ax, (title, group_rows) in zip(axes.flat, panels):
        stability_panel(ax, group_rows, title)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], linestyle="none", marker=m, markersize=10, color="gray",
                          markeredgecolor="black", label=label)
               for m, label in FAILURE_MARKERS.values()]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=10)
    fig.suptitle("Stability map: where each method fails (pi is the largest possible error); "
                 "where lines coincide, each later method's markers sit inside the earlier ones")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=80)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------------------------

def fmt(x, digits=3):
    return f"{x:.{digits}g}" if isinstance(x, float) and math.isfinite(x) else "–"


def step_label(row):
    if row.get("tolerance"):
        return f"tol {fmt(num(row, 'tolerance'))}, output step {fmt(num(row, 'dt'))} s"
    rate = 1.0 / num(row, "dt")
    if row["scene"] in KINEMATIC_SCENES:
        return f"{rate:.0f} Hz samples"
    return f"dt {fmt(num(row, 'dt'))} s"


def cheapest_table(sweep):
    lines = ["| scene | auto | ≤ 1e-6 rad | ≤ 1e-9 rad | ≤ 1e-12 rad |", "|---|---|---|---|---|"]
    for scene in SCENES:
        rows = [r for r in sweep if r["scene"] == scene and r["status"] == "ok"]
        model = model_of(scene)
        auto = sorted({name(r["method"], model) for r in rows if r["auto"] == "1"})
        cells = []
        for tol in TOLERANCES:
            within = [r for r in rows if num(r, "err_rad") <= tol]
            if not within:
                cells.append("none in the sweep")
                continue
            best = min(within, key=work)
            cells.append(f"**{name(best['method'], model)}** ({step_label(best)}): "
                         f"{fmt(work(best) / 1e3)} µs/s, error {fmt(num(best, 'err_rad'), 2)}")
        lines.append(f"| {scene} | {', '.join(auto) or '–'} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def gbench_medians(path):
    with open(path) as f:
        data = json.load(f)
    medians = {}
    for b in data.get("benchmarks", []):
        if b.get("aggregate_name") == "median":
            medians[b["run_name"]] = b["cpu_time"]
        elif "aggregate_name" not in b and b["name"] not in medians:
            medians[b["name"]] = b["cpu_time"]
    return medians


def gbench_spreads(path):
    """Coefficient of variation of each benchmark's repetitions (Google Benchmark's cv)."""
    with open(path) as f:
        data = json.load(f)
    return {b["run_name"]: b["cpu_time"] for b in data.get("benchmarks", [])
            if b.get("aggregate_name") == "cv"}


def cost_table(medians):
    groups = [("kinematicStep", "one kinematic step + normalise (four-sample window)"),
              ("addSample", "KinematicPropagator::addSample (the node's path)"),
              ("engineSubmitCost", "AttitudeEngine::submit of one IMU rate, 200 Hz"),
              ("dynamicStep", "one dynamic step, free body, h = 0.01 s"),
              ("exact", "one exact evaluation at a new time")]
    euler = medians.get("kinematicStep/euler")
    lines = ["| benchmark | what | CPU time [ns] | ratio to kinematicStep/euler |",
             "|---|---|---|---|"]
    for prefix, what in groups:
        for name, ns in medians.items():
            if name.split("/")[0] == prefix:
                ratio = ns / euler if euler else float("nan")
                lines.append(f"| `{name}` | {what} | {ns:.1f} | {ratio:.2f} |")
    return "\n".join(lines)


def targets_table(sweep, medians, node):
    def row(scene, method, dt):
        for r in sweep:
            if r["scene"] == scene and r["method"] == method and abs(num(r, "dt") - dt) < 1e-12:
                return r
        return None

    lines = ["| target | measured | met |", "|---|---|---|"]
    cf4, euler = row("coning", "cf4", 0.005), row("coning", "euler", 0.005)
    if cf4 and euler:
        acc = num(euler, "err_rad") / num(cf4, "err_rad")
        cost = num(cf4, "ns_per_step") / num(euler, "ns_per_step")
        lines.append(f"| cf4 on coning at 200 Hz ≥ 1000× more accurate than euler "
                     f"| {acc:.3g}× ({fmt(num(cf4, 'err_rad'))} against "
                     f"{fmt(num(euler, 'err_rad'))} rad) | {yes(acc >= 1000)} |")
        lines.append(f"| … at ≤ 3× euler's per-step cost (same run, addSample) "
                     f"| {cost:.2f}× ({num(cf4, 'ns_per_step'):.1f} against "
                     f"{num(euler, 'ns_per_step'):.1f} ns) | {yes(cost <= 3)} |")
    e = medians.get("kinematicStep/euler")
    x = medians.get("kinematicStep/exp")
    if e and x:
        lines.append(f"| exp per step ≤ 2.5× euler (Google Benchmark) | {x / e:.2f}× "
                     f"({x:.1f} against {e:.1f} ns) | {yes(x / e <= 2.5)} |")
    for prefix, what in [("kinematicStep", "one step"),
                         ("addSample", "through addSample: time policy, window, step, normalise")]:
        kin = {n: v for n, v in medians.items() if n.split("/")[0] == prefix}
        if kin:
            worst = max(kin, key=kin.get)
            lines.append(f"| every kinematic step < 100 ns ({what}) | slowest `{worst}` "
                         f"{kin[worst]:.1f} ns | {yes(kin[worst] < 100)} |")
    for stamps in ["", "_jittered"]:
        plain = medians.get("engineSubmitCost/default" + stamps)
        filtered = medians.get("engineSubmitCost/sensor_clock" + stamps)
        if plain and filtered:
            lines.append(f"| the stamp filter ≤ 1.5× the default path per message "
                         f"(engineSubmitCost{', jittered stamps' if stamps else ''}) "
                         f"| {filtered / plain:.2f}× ({filtered:.0f} against {plain:.0f} ns) "
                         f"| {yes(filtered / plain <= 1.5)} |")
    rk4 = medians.get("dynamicStep/rk4")
    exact = {n: v for n, v in medians.items() if n.startswith("exact/")}
    for name, ns in exact.items():
        if rk4:
            lines.append(f"| exact evaluation ≤ 10× one dynamic rk4 step | `{name}` "
                         f"{ns / rk4:.2f}× ({ns:.0f} against {rk4:.1f} ns) "
                         f"| {yes(ns / rk4 <= 10)} |")
    lines.extend(node_targets(node))
    return "\n".join(lines)


def yes(ok):
    return "yes" if ok else "**no**"


def node_targets(node):
    if not node:
        return ["| node: 20 kHz, ≥ 99.9 % delivered, p99 < 1 ms | not measured | – |"]
    out = []
    at20 = [r for r in node if r["mode"] == "node" and abs(num(r, "rate_hz") - 20000) < 1]
    if at20:
        r = at20[0]
        frac, p99 = num(r, "delivered_fraction"), num(r, "latency_p99_ms")
        best, worst = num(r, "latency_p99_ms_min"), num(r, "latency_p99_ms_max")
        met = frac >= 0.999 and p99 < 1
        out.append(f"| node: at 20 kHz ≥ 99.9 % reach imu/data, p99 < 1 ms (median of "
                   f"{r['runs']} runs) | {100 * frac:.2f} %, p99 {p99:.3g} ms (runs: "
                   f"{best:.3g}-{worst:.3g} ms) | {yes(met)}"
                   f"{'' if met or best >= 1 else ' (best run: yes)'} |")
    node_max = highest_lossless(node, "node")
    nodelet_max = highest_lossless(node, "nodelet")
    ratio = nodelet_max / node_max if node_max else float("inf")
    out.append(f"| nodelet ≥ 5× the node's highest lossless rate (≥ 99.9 % delivered, "
               f"median of the runs) | nodelet {nodelet_max / 1e3:.0f} kHz, node "
               f"{node_max / 1e3:.0f} kHz: {ratio:.2g}× | {yes(ratio >= 5)} |")
    return out


def highest_lossless(node, mode, threshold=0.999):
    """Highest offered rate up to which every rate delivered >= threshold (median of runs)."""
    best = 0.0
    for r in sorted((r for r in node if r["mode"] == mode), key=lambda r: num(r, "rate_hz")):
        if num(r, "delivered_fraction") < threshold:
            break
        best = num(r, "rate_hz")
    return best


def aggregate_node(rows):
    """Median over the repeated runs of each (mode, rate), with the spread of the runs."""
    groups = defaultdict(list)
    for r in rows:
        groups[(r["mode"], num(r, "rate_hz"))].append(r)
    out = []
    for (mode, rate), group in sorted(groups.items()):
        agg = {"mode": mode, "rate_hz": str(rate), "runs": str(len(group))}
        for key in ("sent_rate_hz", "delivered_fraction", "latency_p50_ms", "latency_p99_ms",
                    "latency_max_ms"):
            values = [num(r, key) for r in group]
            agg[key] = str(statistics.median(values))
            agg[key + "_min"], agg[key + "_max"] = str(min(values)), str(max(values))
        out.append(agg)
    return out


def node_table(node):
    if not node:
        return "Not measured yet (run `bash bench/node_bench.sh`)."
    runs = node[0]["runs"] if node else "?"
    lines = [f"Median of {runs} runs per row (node and nodelet alternating); in brackets the "
             "range over the runs.", "",
             "| mode | offered rate [Hz] | achieved send rate [Hz] | delivered | "
             "latency p50 [ms] | p99 [ms] |", "|---|---|---|---|---|---|"]
    for r in node:
        lines.append(
            f"| {r['mode']} | {num(r, 'rate_hz'):.0f} | {num(r, 'sent_rate_hz'):.0f} "
            f"| {100 * num(r, 'delivered_fraction'):.2f} % "
            f"({100 * num(r, 'delivered_fraction_min'):.1f}-"
            f"{100 * num(r, 'delivered_fraction_max'):.1f}) "
            f"| {fmt(num(r, 'latency_p50_ms'))} | {fmt(num(r, 'latency_p99_ms'))} "
            f"({fmt(num(r, 'latency_p99_ms_min'))}-{fmt(num(r, 'latency_p99_ms_max'))}) |")
    return "\n".join(lines)


def node_chart(node, path):
    fig, axes = plt.subplots(1, 2, figsize=(14, 5))
    for mode, colour in [("node", "tab:blue"), ("nodelet", "tab:green")]:
        rows = sorted([r for r in node if r["mode"] == mode], key=lambda r: num(r, "rate_hz"))
        xs = [num(r, "rate_hz") for r in rows]
        axes[0].plot(xs, [100 * num(r, "delivered_fraction") for r in rows], marker="o",
                     color=colour, label=mode)
        axes[1].plot(xs, [num(r, "latency_p50_ms") for r in rows], marker="o", color=colour,
                     label=f"{mode} p50")
        axes[1].plot(xs, [num(r, "latency_p99_ms") for r in rows], marker="^", color=colour,
                     linestyle="--", label=f"{mode} p99")
        axes[1].fill_between(xs, [num(r, "latency_p99_ms_min") for r in rows],
                             [num(r, "latency_p99_ms_max") for r in rows], color=colour,
                             alpha=0.12, label=f"{mode} p99, range over runs")
        axes[0].fill_between(xs, [100 * num(r, "delivered_fraction_min") for r in rows],
                             [100 * num(r, "delivered_fraction_max") for r in rows],
                             color=colour, alpha=0.12)
    axes[0].axhline(99.9, color="gray", linestyle=":", label="99.9 %")
    axes[0].set_ylabel("messages that reached imu/data [%]")
    axes[1].axhline(1.0, color="gray", linestyle=":", label="1 ms")
    axes[1].set_yscale("log")
    axes[1].set_ylabel("input-to-output latency [ms]")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("offered IMU rate [Hz]")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=9)
    axes[0].set_title("delivery")
    axes[1].set_title("latency (input header stamped at send time)")
    fig.suptitle("Node benchmark: sensor_msgs/Imu in, imu/data out (median of the runs)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------

def find(sweep, scene, method, dt=None, tolerance=None):
    for r in sweep:
        if r["scene"] != scene or r["method"] != method:
            continue
        if dt is not None and abs(num(r, "dt") - dt) > 1e-12 * max(dt, 1.0):
            continue
        if tolerance is not None and abs(num(r, "tolerance") - tolerance) > 1e-3 * tolerance:
            continue
        return r
    return None


def err_at(sweep, scene, method, dt):
    r = find(sweep, scene, method, dt=dt)
    return fmt(num(r, "err_rad"), 2) if r else "–"


# `auto` holds in a cell (scene, tolerance) when its method's cheapest run within the tolerance
# costs at most this factor more than the cheapest run of any method.
AUTO_SLACK = 2.0
ROUND_OFF = 1e-13  # rad, or 0.1 eps per step when more: an error this small is round-off
EPS = 2.220446049250313e-16
KEPT = 1e-12  # a relative drift of an invariant this small over the long run: kept


def round_off(row):
    """The error a run may carry from rounding alone: ROUND_OFF, or 0.1 eps per step."""
    return max(ROUND_OFF, 0.1 * EPS * num(row, "steps"))


def cheapest_within(rows, tol):
    within = [r for r in rows if r["status"] == "ok" and num(r, "err_rad") <= tol]
    return min(within, key=work) if within else None


def auto_cells(sweep, scenes):
    """For each scene and tolerance the sweep reaches: (scene, tol, best run, auto's best run)."""
    cells = []
    for scene in scenes:
        rows = [r for r in sweep if r["scene"] == scene]
        auto = [r for r in rows if r["auto"] == "1"]
        for tol in TOLERANCES:
            best = cheapest_within(rows, tol)
            if best:
                cells.append((scene, tol, best, cheapest_within(auto, tol)))
    return cells


def round_off_methods(rows):
    """Methods whose every run of the scene stays within ROUND_OFF (exact at any step)."""
    return [m for m, g in by_method(rows).items()
            if all(r["status"] == "ok" and num(r, "err_rad") <= round_off(r) for r in g)]


def quoted(methods, model=None):
    return ", ".join(called(m, model) for m in methods) or "none"


def choice_lines(sweep, method, scenes):
    """What the measurements say of `auto` picking `method` on `scenes`."""
    model = model_of(scenes[0])
    me = called(method, model)
    cells = auto_cells(sweep, scenes)
    cheapest = [c for c in cells if c[3] and c[3] is c[2]]
    close = [c for c in cells if c[3] and c[3] is not c[2] and
             work(c[3]) <= AUTO_SLACK * work(c[2])]
    beaten = [c for c in cells if c not in cheapest and c not in close]
    verdict = "keep it" if not beaten else "keep it except where another method is cheaper"
    text = (f"- **{me}** ({', '.join(scenes)}): the cheapest method in {len(cheapest)} of "
            f"the {len(cells)} (scene, tolerance) cells the sweep reaches, within "
            f"{AUTO_SLACK:g}× of it in {len(close)}; {verdict}.")
    # One sentence per scene and pair of runs, with every tolerance where they are the pair.
    pairs = defaultdict(list)
    for scene, tol, best, mine in beaten:
        pairs[(scene, id(best), id(mine))].append((tol, best, mine))
    for (scene, _, _), group in pairs.items():
        tols = [f"{tol:g}" for tol, _, _ in group]
        _, best, mine = group[0]
        within = (tols[0] if len(tols) == 1 else
                  ", ".join(tols[:-1]) + f" and {tols[-1]}")
        against = (f"{fmt(work(mine) / 1e3)} µs/s for {me}" if mine
                   else f"{me} does not reach it in the sweep")
        text += (f" On {scene} to ≤ {within} rad {called(best['method'], model)} "
                 f"({step_label(best)}) costs {fmt(work(best) / 1e3)} µs/s ({against}): "
                 f"`integrator: {best['method']}` there"
                 + (f" saves {fmt((work(mine) - work(best)) / 1e3, 2)} µs of CPU per "
                    "simulated second." if mine else " reaches it."))
    return text


def accuracy_lines(sweep, method, scenes):
    """At each step of the scenes, whether `method` is the most accurate, and what it buys over
    the method cheapest per step."""
    lines = []
    wins = total = 0
    gains = []
    for scene in scenes:
        rows = [r for r in sweep if r["scene"] == scene and r["status"] == "ok" and
                not is_tolerance_sweep([r])]
        for dt in sorted({num(r, "dt") for r in rows}):
            at = [r for r in rows if num(r, "dt") == dt]
            mine = [r for r in at if r["method"] == method]
            if not mine:
                continue
            total += 1
            best = min(at, key=lambda r: num(r, "err_rad"))
            # Errors within round-off of each other tie.
            wins += num(mine[0], "err_rad") <= max(num(best, "err_rad"), round_off(mine[0]))
            cheap = min(at, key=lambda r: num(r, "ns_per_step"))
            if cheap is not mine[0] and num(cheap, "err_rad") > round_off(cheap):
                gains.append((num(cheap, "err_rad") / max(num(mine[0], "err_rad"), FLOOR),
                              num(mine[0], "ns_per_step") - num(cheap, "ns_per_step"),
                              cheap["method"]))
    model = model_of(scenes[0])
    if total:
        lines.append(f"  {called(method, model)} is the most accurate method (ties within "
                     "round-off) at "
                     f"{wins} of the {total} steps swept on {', '.join(scenes)}.")
    if gains:
        low, high = min(g[0] for g in gains), max(g[0] for g in gains)
        extra = [g[1] for g in gains]
        lines.append(f"  Against the method cheapest per step where that one is not exact "
                     f"({quoted(sorted({g[2] for g in gains}), model)}) it is "
                     f"{math.log10(low):.1f}-{math.log10(high):.1f} orders of magnitude more "
                     f"accurate for {min(extra):.0f}-{max(extra):.0f} ns more per step.")
    return lines


def exact_lines(sweep, scenes):
    """Methods exact to round-off at every step, per scene, and the cheapest of them."""
    lines = []
    for scene in scenes:
        rows = [r for r in sweep if r["scene"] == scene]
        exact = round_off_methods(rows)
        if not exact:
            continue
        runs = [r for r in rows if r["method"] in exact]
        cheapest = min(runs, key=work)
        worst = max(num(r, "err_rad") for r in runs)
        duration = max(num(r, "dt") * num(r, "steps") for r in runs)
        model = model_of(scene)
        lines.append(f"  On {scene} {quoted(exact, model)} "
                     f"{'stays' if len(exact) == 1 else 'stay'} "
                     f"within round-off at every step (largest {fmt(worst, 2)} rad over "
                     f"{duration:.0f} s); the cheapest is {called(cheapest['method'], model)} "
                     f"({step_label(cheapest)}, {fmt(work(cheapest) / 1e3)} µs/s).")
    return lines


def numerical_best_lines(sweep, scenes, exact_method):
    """The best any other method reaches on scenes where the exact solution runs."""
    lines = []
    for scene in scenes:
        rows = [r for r in sweep if r["scene"] == scene and r["method"] != exact_method and
                r["status"] == "ok"]
        if not rows:
            continue
        best = min(rows, key=lambda r: num(r, "err_rad"))
        lines.append(f"  The most accurate other run on {scene}: "
                     f"{called(best['method'], model_of(scene))} "
                     f"({step_label(best)}) at {fmt(num(best, 'err_rad'), 2)} rad.")
    return lines


def exact_cost_line(sweep, method):
    rows = [r for r in sweep if r["method"] == method]
    if not rows:
        return []
    costs = sorted(num(r, "ns_per_step") for r in rows)
    return [f"  One {called(method, 'dynamic')} step costs {costs[0]:.0f}-{costs[-1]:.0f} ns, "
            "at most "
            f"{costs[-1] * 100 / 1e3:.0f} µs of CPU per simulated second at 100 steps per "
            "second."]


def invariant_lines(sweep, invariants):
    """Methods that keep |M| or the energy to round-off over the long run, and whether they are
    beaten per unit of CPU: on a scene, a run is beaten when another method's run is both
    cheaper and more accurate."""
    if not invariants:
        return []
    keeps = {}
    for method, group in by_method(invariants).items():
        kept = [label for key, label in [("momentum_rel_drift", "|M|"),
                                         ("energy_rel_drift", "the energy")]
                if max(num(r, key) for r in group) <= KEPT]
        if kept:
            keeps[method] = kept
    if not keeps:
        return []
    t_end = max(num(r, "t") for r in invariants)
    parts = [f"{called(m, 'dynamic')} keeps {' and '.join(k)}" for m, k in keeps.items()]
    lines = [f"- **Invariants** (free body, {t_end:.0f} s): " + "; ".join(parts) +
             f" to {KEPT:g} relative."]
    for method in keeps:
        beaten_on, scenes = [], sorted({r["scene"] for r in sweep if r["method"] == method})
        for scene in scenes:
            rows = [r for r in sweep if r["scene"] == scene and r["status"] == "ok"]
            mine = [r for r in rows if r["method"] == method]
            others = [r for r in rows if r["method"] != method]
            if mine and all(any(work(o) <= work(r) and num(o, "err_rad") <= num(r, "err_rad")
                                for o in others) for r in mine):
                beaten_on.append(scene)
        lines.append(f"  {called(method, 'dynamic')}: every run beaten by a cheaper, more "
                     "accurate one on "
                     f"{len(beaten_on)} of {len(scenes)} scenes"
                     f"{' (' + ', '.join(beaten_on) + ')' if beaten_on else ''}.")
    return lines


# ---------------------------------------------------------------------------------------------
# Real streams (real_streams.csv): `auto` against the best method per stream, and the settings
# per stream of docs/real_streams.md.
# ---------------------------------------------------------------------------------------------

STREAM_SLACK = 1.5  # `auto` holds on a stream when its error is within this of the best method's


def stream_cells(streams):
    """(scene, stream, rate_hz) -> (the best kinematic method's row, auto's row)."""
    groups = defaultdict(list)
    for r in streams:
        groups[(r["scene"], r["stream"], r["rate_hz"])].append(r)
    cells = {}
    for key, rows in groups.items():
        methods = [r for r in rows if r["method"] != "auto"]
        auto = next((r for r in rows if r["method"] == "auto"), None)
        if auto is not None and methods:
            cells[key] = (min(methods, key=lambda r: num(r, "err_rad")), auto)
    return cells


def stream_ratio(best, auto):
    return max(num(auto, "err_rad"), FLOOR) / max(num(best, "err_rad"), FLOOR)


def stream_label(stream, rate):
    return f"`{stream}` {rate} Hz" if stream in ("point", "averaged_end") else f"`{stream}`"


def jitter_range(cells, switched):
    """The smallest (switched) or largest (not) jitter measure J of auto on the streams read
    without the stamp filter (with it the jitter rule is off) and with some stamp noise."""
    values = [num(auto, "auto_jitter") for (best, auto) in cells.values()
              if auto["stamp_filter"] == "none" and num(auto, "auto_jitter") > 1e-9 and
              ("rk4" in auto["auto_used"] or "exp2" in auto["auto_used"]) == switched and
              "drops" not in auto["stream"]]
    if not values:
        return "–"
    return fmt(min(values) if switched else max(values), 2)


def stream_verdict(streams):
    """`auto` on every stream of real_streams.csv against the best kinematic method there."""
    cells = stream_cells(streams)
    if not cells:
        return []
    scenes = list(dict.fromkeys(r["scene"] for r in streams))
    keys = list(dict.fromkeys((r["stream"], r["rate_hz"]) for r in streams))
    ratios = {k: stream_ratio(*v) for k, v in cells.items()}
    held = sum(1 for v in ratios.values() if v <= STREAM_SLACK)
    worst_key = max(ratios, key=ratios.get)
    lines = [
        "",
        "**On the real streams** (`real_streams.csv`, `bench_sweep --streams`; the streams in "
        "[real_streams.md](docs/real_streams.md)). `auto` chooses per stream "
        "(`src/core/numerics/auto_integrator.cpp`): `cf4`, but `exp2` for the steps whose window holds "
        f"an interval mean filled in for a lost one, and {called('rk4', 'kinematic')} (point "
        "samples) or `exp2` "
        "(means) while the jitter measure J = σ_t |Δω|_rms / (h |ω|_rms) exceeds 2e-3 and "
        "the body turns (mean rate ≥ 0.1 |ω|_rms), without the stamp filter. "
        f"Each cell: `auto`'s largest error over the best method's on that stream, and the "
        f"methods `auto` integrated with; **bold** beyond {STREAM_SLACK:g}×. `auto` is within "
        f"{STREAM_SLACK:g}× of the best on {held} of {len(ratios)} streams (worst "
        f"{ratios[worst_key]:.2f}×: {worst_key[1]} at {worst_key[2]} Hz on {worst_key[0]}). "
        f"J on the streams with stamp noise read without the stamp filter: at most "
        f"{jitter_range(cells, False)} where `auto` stayed on `cf4`, at least "
        f"{jitter_range(cells, True)} where it switched.",
        "",
        "| stream | " + " | ".join(scenes) + " |",
        "|---|" + "---|" * len(scenes),
    ]
    for stream, rate in keys:
        row = []
        for scene in scenes:
            cell = cells.get((scene, stream, rate))
            if cell is None:
                row.append("–")
                continue
            best, auto = cell
            ratio = ratios[(scene, stream, rate)]
            text = f"{ratio:.2f}"
            if ratio > STREAM_SLACK:
                text = f"**{text}**"
            text += " " + "+".join(name(m, "kinematic") for m in auto["auto_used"].split("+"))
            if ratio > 1.005 and best["method"] not in auto["auto_used"].split("+"):
                text += f" (best {name(best['method'], 'kinematic')})"
            row.append(text)
        lines.append(f"| {stream_label(stream, rate)} | " + " | ".join(row) + " |")
    return lines


# What a gyro delivers (200 Hz unless named), the streams read with the settings and with the
# defaults (as a plain point-sample reading), and what the row says.
SETTINGS_ROWS = [
    ("point samples, hardware stamps", "point", None),
    ("means stamped at the interval's end (delta-angle / dt)", "averaged_end",
     "averaged_end_as_point"),
    ("means stamped at the interval's midpoint", "averaged_mid", "averaged_mid_as_end"),
    ("means stamped at the interval's start", "averaged_start", "averaged_start_as_end"),
    ("rates through a 2nd-order Butterworth at ODR/4", "butterworth2_odr4_rate_delay",
     "butterworth2_odr4"),
    ("rates through a sinc³ decimator by 8", "sinc3_r8_rate_delay", "sinc3_r8"),
    ("receipt stamps, latency 0.1 ms (exponential: mean and sd)", "jitter_0.1ms_sensor_clock",
     "jitter_0.1ms"),
    ("receipt stamps, latency 1 ms (exponential: mean and sd; 400 Hz)", "jitter_1ms_400Hz",
     "jitter_1ms_400Hz_sensor_clock"),
    ("FIFO reads of 10, every sample with the read's receipt stamp",
     "fifo10_repeated_sensor_clock", "fifo10_repeated"),
    ("FIFO reads of 10, receipt stamp less k periods", "fifo10_spaced_sensor_clock",
     "fifo10_spaced"),
    ("a rate change 200 → 1000 Hz, hardware stamps", "rate_change_200_1000Hz",
     "rate_change_200_1000Hz_sensor_clock"),
    ("means with 5 % lost", "drops_5pct_averaged", "drops_5pct_averaged_no_fill"),
    ("noisy MEMS means (angle random walk, quantisation)", "mems_averaged", None),
]


def settings_of(row):
    """The non-default settings a stream was read with, as parameters."""
    parts = []
    if row["rate_samples"] != "instantaneous":
        parts.append(f"`rate_samples: {row['rate_samples']}`")
    if row["average_stamp"] != "end":
        parts.append(f"`average_stamp: {row['average_stamp']}`")
    if row["stamp_filter"] != "none":
        parts.append(f"`stamp_filter: {row['stamp_filter']}`")
    if num(row, "rate_delay_s") > 0:
        parts.append(f"`rate_delay: {num(row, 'rate_delay_s'):.5f}`")
    if row["max_gap_fill"] != "4":
        parts.append(f"`max_gap_fill: {row['max_gap_fill']}`")
    return ", ".join(parts) or "the defaults"


def settings_table(streams):
    """Which settings per stream, with `auto`'s error (median over seeds) read so and read
    otherwise, on every scene."""
    autos = {(r["scene"], r["stream"], r["rate_hz"]): r for r in streams if r["method"] == "auto"}
    scenes = list(dict.fromkeys(r["scene"] for r in streams))
    rate_of = {r["stream"]: r["rate_hz"] for r in streams}
    cells = stream_cells(streams)
    held = sum(1 for best, auto in cells.values() if stream_ratio(best, auto) <= STREAM_SLACK)
    lines = [f"Keep `integrator: auto` on every stream: it is within {STREAM_SLACK:g}× of the "
             f"best method's error on {held} of the {len(cells)} streams and scenes (chart "
             "below); what a stream needs is its settings:", "",
             "| stream | settings | `auto`'s error with them, rad (" + ", ".join(scenes) +
             ") | read otherwise |", "|---|---|---|---|"]
    for label, with_, without in SETTINGS_ROWS:
        rate = "200" if with_ in ("point", "averaged_end") else rate_of.get(with_)
        row = autos.get((scenes[0], with_, rate))
        if row is None:
            continue
        errs = " / ".join(fmt(num(autos[(s, with_, rate)], "err_rad"), 2) for s in scenes)
        other = "–"
        if without is not None and (scenes[0], without, rate_of.get(without)) in autos:
            alt = autos[(scenes[0], without, rate_of[without])]
            other = (settings_of(alt) + ": " + " / ".join(
                fmt(num(autos[(s, without, rate_of[without])], "err_rad"), 2) for s in scenes))
        lines.append(f"| {label} | {settings_of(row)} | {errs} | {other} |")
    return "\n".join(lines) + "\n"



def verdict(sweep, invariants, streams=()):
    """`auto`'s choices against the measurements: every claim computed from the rows."""
    lines = ["### `auto` against the measurements", "",
             f"`auto` holds in a (scene, tolerance) cell of the table above when its method is "
             f"the cheapest there or within {AUTO_SLACK:g}× of it.", ""]
    by_choice = defaultdict(list)
    for scene in SCENES:
        for m in sorted({r["method"] for r in sweep if r["scene"] == scene and r["auto"] == "1"}):
            by_choice[m].append(scene)
    for method, scenes in by_choice.items():
        lines.append(choice_lines(sweep, method, scenes))
        if all(s in KINEMATIC_SCENES for s in scenes):
            lines += accuracy_lines(sweep, method, scenes)
            lines += exact_lines(sweep, scenes)
        elif all(method in round_off_methods([r for r in sweep if r["scene"] == s])
                 for s in scenes):
            lines += exact_lines(sweep, scenes)
            lines += exact_cost_line(sweep, method)
            lines += numerical_best_lines(sweep, scenes, method)
    lines += invariant_lines(sweep, invariants)
    lines += stream_verdict(streams)
    lines.append("")
    return "\n".join(lines)


def machine_line(data_dir):
    path = os.path.join(data_dir, "machine.txt")
    if not os.path.exists(path):
        return "the development machine"
    with open(path) as f:
        info = dict(line.strip().split(": ", 1) for line in f if ": " in line)
    return (f"{info.get('cpu', '?')} ({info.get('date', '?')}, commit "
            f"{info.get('commit', '?')}, load average {info.get('load before the run', '?')})")


def spread_sentence(spreads):
    """The spread of the Google Benchmark repetitions (coefficient of variation), if known."""
    if not spreads:
        return ""
    return (f"Within this run the repetitions of one step's timing spread by "
            f"{100 * min(spreads.values()):.1f}-{100 * max(spreads.values()):.1f} % "
            "(coefficient of variation). ")


def queue_sentence(node):
    """Latency at the highest offered rate against the time a full input queue takes to drain."""
    if not node:
        return ""
    top = max(node, key=lambda r: (num(r, "rate_hz"), r["mode"]))
    rate = num(top, "rate_hz")
    return (f"At the highest offered rate ({rate / 1e3:.0f} kHz, {top['mode']}) the median "
            f"latency is {fmt(num(top, 'latency_p50_ms'))} ms, against "
            f"{1e3 * NODE_QUEUE / rate:.3g} ms for a full queue to drain at that rate. ")


def p99_spread_sentence(node):
    ratios = [num(r, "latency_p99_ms_max") / num(r, "latency_p99_ms_min") for r in node
              if num(r, "latency_p99_ms_min") > 0]
    if not ratios:
        return ""
    return (f"Between runs the p99 at one rate varies by up to {max(ratios):.3g}× "
            "(the machine is shared): read the ranges.")


NODE_QUEUE = 10000  # messages: the node's input queue (attitude_propagator_ros)


def both_models_sentence(sweep):
    """The sentence on a setting that names a method in each model (rk4), with the orders the
    sweep measured."""
    out = ""
    for method in sorted(BOTH_MODELS):
        orders = model_orders(sweep, method)
        if len(orders) < 2:
            continue
        out += (f" `integrator: {method}` names two methods, charted and named apart: "
                + " and ".join(f"{model} `{method}` (order {p:.1f} measured here)"
                               for model, p in orders) +
                "; the kinematic one has only the rate samples, so its midpoint rate is "
                "interpolated ([numerics.md](docs/numerics.md) §2, §5).")
    return out


def results_markdown(sweep, medians, node, has_node_chart, machine, invariants=(),
                     spreads=None, streams=()):
    parts = [
        "## Benchmarks: speed against accuracy",
        "",
        "Regenerate everything below with one command (the build, the sweep, Google Benchmark, "
        "the node benchmark, the charts):",
        "",
        "```bash",
        "bash bench/run_all.sh      # --no-node skips the node benchmark (bench/node_bench.sh)",
        "```",
        "",
        "The charts and the text alone, from the data already in `docs/data/` (seconds, no "
        "build): `/usr/bin/python3 bench/plot.py docs/data docs docs/benchmarks.md`.",
        "",
        f"Measured on {machine}; costs are CPU time of the benchmark thread, and methods are "
        "timed in turn within one run, so that load from other processes falls on all of them. "
        f"{spread_sentence(spreads)}"
        "Raw data: `docs/data/*.csv`, `docs/data/step_costs.json`.",
        "",
        "### Which setting to pick",
        "",
        advice_markdown(medians, node, sweep) + both_models_sentence(sweep),
        "",
        "### Which integrator: cheapest method within a tolerance",
        "",
        "For each scene, the cheapest (step, method) of the sweep whose largest attitude error "
        "along the whole path stays within 1e-6, 1e-9 and 1e-12 rad; cost in µs of CPU per "
        "simulated second. For the kinematic scenes the step is the gyro's sample period, "
        "which the sensor usually fixes: read the chart at your rate.",
        "",
        cheapest_table(sweep),
        "",
        verdict(sweep, invariants, streams),
        "### Targets",
        "",
        targets_table(sweep, medians, node),
        "",
        "### Charts",
        "",
        "![work-precision](docs/work_precision.png)",
        "",
        "Error against cost per scene: keep `auto` (the thick line); a line that sits on "
        "another is dashed with hollow markers, and its label names the line below.",
        "",
        "![order](docs/order.png)",
        "",
        "Error against step, each method's measured order in its label.",
        "",
        "![invariants](docs/invariants.png)",
        "",
        "The energy and |angular momentum| over a long free-body run.",
        "",
        "![stability](docs/stability.png)",
        "",
        "The error after a fixed time against |Ω| h, and where each method fails; where "
        "lines coincide, each later method's markers sit inside the earlier ones.",
        "",
        "### Cost of one step (Google Benchmark, median CPU time of 7 repetitions)",
        "",
        cost_table(medians) if medians else "Not measured.",
        "",
        "### Node throughput and latency",
        "",
        "`bash bench/node_bench.sh` (run by `bench/run_all.sh`): a load generator publishes "
        "`sensor_msgs/Imu` on `imu/data_raw` at each offered rate for 3 s, header stamped at "
        "send time, and measures on `imu/data` (which carries the input header) the fraction "
        "delivered and now − stamp. `node`: generator and `attitude_propagator_node` are "
        "separate processes (TCP). `nodelet`: the generator is a nodelet "
        "(`bench/bench_nodelets.xml`) in the same manager as the propagator nodelet and "
        "publishes shared pointers (no serialisation). Defaults of `config/default.yaml` "
        "(kinematic, `cf4`, tf on): per input the wrapper publishes tf, `attitude_state` and "
        f"`imu/data`. When the propagator cannot keep up, its input queue ({NODE_QUEUE} "
        "messages) fills and the excess is dropped. " + queue_sentence(node) +
        p99_spread_sentence(node),
        "",
        node_table(node),
    ]
    if has_node_chart:
        parts += ["", "![node benchmark](docs/node_bench.png)"]
    return "\n".join(parts) + "\n"


def charts_relative_to(text, docs_dir, folder):
    """TEXT names the charts as docs/NAME.png (from the repository root); this names them
    from FOLDER instead."""
    rel = os.path.relpath(os.path.abspath(docs_dir), os.path.abspath(folder))
    return text.replace("](docs/", "](" if rel == os.curdir else "](" + rel + "/")


def splice_page(page, text, docs_dir, marker="results"):
    begin, end = f"<!-- >>> {marker} -->", f"<!-- <<< {marker} -->"
    with open(page) as f:
        content = f.read()
    if content.count(begin) != 1 or content.count(end) != 1:
        raise SystemExit(f"plot.py: {page} needs one {begin} and one {end} marker")
    head, rest = content.split(begin, 1)
    _, tail = rest.split(end, 1)
    text = charts_relative_to(text, docs_dir, os.path.dirname(os.path.abspath(page)))
    with open(page, "w") as f:
        f.write(head + begin + "\n" + text + end + tail)


# The streams of real_streams.csv by what the gyro delivers (first matching prefix), in the
# chart's order.
STREAM_FAMILIES = [
    (("point",), "point samples"),
    (("averaged",), "interval means"),
    (("butterworth", "sinc"), "filtered rates"),
    (("jitter",), "receipt stamps, latency"),
    (("fifo",), "FIFO reads"),
    (("rate_change",), "rate change"),
    (("drops",), "lost means"),
    (("mems",), "noisy MEMS means"),
]


def stream_family(stream):
    for prefixes, family in STREAM_FAMILIES:
        if stream.startswith(prefixes):
            return family
    return "other"


def ratio_text(ratio):
    if ratio < 9.95:
        return f"{ratio:.2g}" if ratio < 0.995 or ratio >= 1.005 else "1"
    if ratio < 999.5:
        return f"{ratio:.0f}"
    return f"{ratio:.0e}".replace("e+0", "e")


def real_streams_chart(rows, path, advice=""):
    """Which method on which stream: per scene (one panel each), a grid of streams (rows,
    grouped by what the gyro delivers) against methods (columns, `auto` last and framed), each
    cell the method's largest error (median over seeds) over the best method's on that stream,
    so 1 marks the method to pick; the absolute errors are in docs/real_streams.md's table."""
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Rectangle

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    keys = list(dict.fromkeys((r["stream"], r["rate_hz"]) for r in rows))
    families = [f for _, f in STREAM_FAMILIES] + ["other"]
    keys.sort(key=lambda k: families.index(stream_family(k[0])))  # stable: the csv's order within
    methods = [m for m in dict.fromkeys(r["method"] for r in rows) if m != "auto"] + ["auto"]
    cells = stream_cells(rows)
    held = sum(1 for best, auto in cells.values() if stream_ratio(best, auto) <= STREAM_SLACK)
    norm = LogNorm(vmin=1.0, vmax=100.0)
    cmap = plt.get_cmap("YlOrRd")
    height = 2.8 + 0.3 * len(keys)
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.5 + 3.9 * len(scenes), height),
                             sharey=True, squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        mine = {(r["stream"], r["rate_hz"], r["method"]): r for r in rows if r["scene"] == scene}
        grid = []
        for i, (stream, rate) in enumerate(keys):
            errs = {m: max(num(mine[(stream, rate, m)], "err_rad"), FLOOR) for m in methods
                    if (stream, rate, m) in mine}
            others = [e for m, e in errs.items() if m != "auto"]
            best = min(others) if others else float("nan")
            line = []
            for j, method in enumerate(methods):
                ratio = errs[method] / best if method in errs else float("nan")
                line.append(max(ratio, 1.0))
                if math.isnan(ratio):
                    continue
                winner = method != "auto" and errs[method] == best
                ax.text(j, i, ratio_text(ratio), ha="center", va="center", fontsize=8,
                        fontweight="bold" if winner or (method == "auto" and
                                                        ratio <= STREAM_SLACK) else "normal",
                        color="white" if ratio > 30 else "black")
            grid.append(line)
        ax.imshow(grid, cmap=cmap, norm=norm, aspect="auto", interpolation="nearest")
        ax.add_patch(Rectangle((len(methods) - 1.5, -0.5), 1.0, len(keys), fill=False,
                               edgecolor="black", linewidth=2.5, clip_on=False))
        ax.set_xticks(range(len(methods)))
        ax.set_xticklabels([name(m, "kinematic").replace(" ", "\n") for m in methods],
                           fontsize=9)
        for tick, method in zip(ax.get_xticklabels(), methods):
            tick.set_color("black" if method == "auto" else style(method, "kinematic")[0])
            tick.set_fontweight("bold")
        ax.xaxis.tick_top()
        mine_held = sum(1 for (s, _, _), (best, auto) in cells.items()
                        if s == scene and stream_ratio(best, auto) <= STREAM_SLACK)
        mine_all = sum(1 for (s, _, _) in cells if s == scene)
        ax.set_title(f"{scene}\nauto within {STREAM_SLACK:g}x of the best on {mine_held} of "
                     f"{mine_all}", fontsize=10)
        for i in range(1, len(keys)):
            if stream_family(keys[i][0]) != stream_family(keys[i - 1][0]):
                ax.axhline(i - 0.5, color="black", linewidth=1.2)
        ax.tick_params(length=0)
    labels = []
    for stream, rate in keys:
        autos = [r for r in rows if r["stream"] == stream and r["rate_hz"] == rate and
                 r["method"] == "auto"]
        settings = settings_of(autos[0]).replace("`", "") if autos else ""
        label = f"{stream.replace('_', ' ')}, {rate} Hz"
        labels.append(label + ("" if settings == "the defaults" else f"  [{settings}]"))
    axes[0][0].set_yticks(range(len(keys)))
    axes[0][0].set_yticklabels(labels, fontsize=8.5)
    previous = None
    for i, (stream, _) in enumerate(keys):
        family = stream_family(stream)
        if family != previous:
            axes[0][-1].annotate(family, xy=(1.02, i - 0.45), xycoords=("axes fraction", "data"),
                                 fontsize=9, fontweight="bold", va="top", annotation_clip=False)
            previous = family
    fig.suptitle("Which method on which stream: each method's largest error over the best "
                 "method's on that stream (1 = the best, bold; median over seeds)\n"
                 f"Keep `auto` (framed column): within {STREAM_SLACK:g}x of the best on "
                 f"{held} of {len(cells)} streams and scenes" +
                 (f";\n{advice}." if advice else "."), fontsize=12)
    fig.tight_layout(rect=(0, 0, 0.94, 1))
    fig.savefig(path, dpi=75)
    plt.close(fig)


def fixes_chart(rows, path):
    """Late absolute fixes on the simulated gyro (fixes.csv, bench_sweep --fixes): the body-frame
    attitude error per axis with its 3 sigma bound, with and without the gyro bias estimate, and
    the bias estimate's error with its 3 sigma."""
    colours = ["tab:red", "tab:green", "tab:blue"]
    runs = [("bias_estimated", "attitude error, fuse with estimate_gyro_bias"),
            ("bias_not_estimated", "attitude error, fuse without the bias estimate")]
    fig, axes = plt.subplots(3, 1, figsize=(11, 11), sharex=True)
    for ax, (run, title) in zip(axes[:2], runs):
        mine = [r for r in rows if r["run"] == run]
        t = [num(r, "t") for r in mine]
        for colour, axis in zip(colours, "xyz"):
            ax.plot(t, [1e3 * num(r, "err_" + axis) for r in mine], color=colour, linewidth=0.7,
                    label=f"error about {axis}")
            bound = [3e3 * num(r, "sd_" + axis) for r in mine]
            ax.plot(t, bound, color=colour, linestyle="dashed", linewidth=0.8,
                    label=f"3 sigma about {axis}")
            ax.plot(t, [-b for b in bound], color=colour, linestyle="dashed", linewidth=0.8)
        ax.set_ylabel("mrad (body frame)")
        ax.set_title(title)
        ax.set_ylim(-1.5, 1.5)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=3, loc="upper right")
    ax = axes[2]
    mine = [r for r in rows if r["run"] == "bias_estimated"]
    t = [num(r, "t") for r in mine]
    for colour, axis in zip(colours, "xyz"):
        ax.plot(t, [num(r, "bias_err_" + axis) for r in mine], color=colour, linewidth=0.8,
                label=f"bias error, {axis}")
        bound = [3 * num(r, "bias_sd_" + axis) for r in mine]
        ax.plot(t, bound, color=colour, linestyle="dashed", linewidth=0.8,
                label=f"3 sigma, {axis}")
        ax.plot(t, [-b for b in bound], color=colour, linestyle="dashed", linewidth=0.8)
    ax.set_ylabel("deg/h")
    ax.set_ylim(-16, 16)
    ax.set_xlabel("time (s)")
    ax.set_title("gyro bias estimate's error (true bias 10 deg/h)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=3, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    plt.close(fig)


AHRS_STREAMS = [("handheld", "handheld tumble (tilt to 52 deg, 2 m/s^2; accel_stddev chosen here)"),
                ("vehicle", "vehicle (turns to 2.6 m/s^2, braking)"),
                ("vehicle_mag", "vehicle + magnetometer (field turned 30 deg at 150 s)"),
                ("vehicle2", "second vehicle, held out"),
                ("vehicle2_mag", "second vehicle + magnetometer, held out (field turned 30 deg at "
                 "150 s)"),
                ("boat", "boat, held out (swells, heave)")]
# The streams with a magnetometer, whose heading gets a panel of its own.
AHRS_HEADING = [("vehicle_mag", "vehicle + magnetometer: heading"),
                ("vehicle2_mag", "second vehicle + magnetometer, held out: heading")]


def rms_of(values):
    values = [v for v in values if not math.isnan(v)]
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float("nan")


def ahrs_label(name, stream):
    """engine_accel_stddev_2 -> the engine and its setting; madgwick_beta_0.01 -> the peer."""
    if name.startswith("engine_accel_stddev_"):
        value = name[len("engine_accel_stddev_"):]
        aids = "use_accel" + (", use_mag" if stream.endswith("_mag") else "")
        which = "the sensor's" if value == "0.05" else "chosen on handheld"
        return f"engine ({aids}, accel_stddev {value}: {which})"
    return "Madgwick beta " + name[len("madgwick_beta_"):] + " (best of 4 gains)"


def ahrs_chart(rows, path, settle=10.0):
    """The engine (use_accel, use_mag on the field's stream, the bias estimated; accel_stddev at
    the sensor's value and at the one chosen on the handheld stream) against the best-gain
    Madgwick filter (ahrs.csv, bench_ahrs): the tilt error per stream over time and the heading
    error on the magnetometer's stream, each series' RMS after `settle` s in its label; the title
    says which filter had the lower RMS on how many panels."""
    panels = [(stream, "tilt_deg", title + ": tilt") for stream, title in AHRS_STREAMS]
    panels += [(stream, "heading_deg", title) for stream, title in AHRS_HEADING]
    fig, axes = plt.subplots(len(panels), 1, figsize=(11, 3.4 * len(panels)))
    wins = []
    for ax, (stream, column, title) in zip(axes, panels):
        short = stream.replace("_mag", " + mag") + (" heading" if column == "heading_deg" else
                                                    " tilt")
        mine = [r for r in rows if r["stream"] == stream]
        scores = {}
        for name in dict.fromkeys(r["filter"] for r in mine):
            series = [r for r in mine if r["filter"] == name]
            t = [num(r, "t") for r in series]
            y = [num(r, column) for r in series]
            scores[name] = rms_of([v for v, tt in zip(y, t) if tt >= settle])
            colour, width = (("tab:orange", 0.8) if name.startswith("madgwick") else
                             ("tab:gray", 0.5) if name.endswith("_0.05") else ("tab:blue", 0.8))
            ax.plot(t, y, color=colour, linewidth=width,
                    label=f"{ahrs_label(name, stream)}: RMS {scores[name]:.3g} deg")
        if stream.endswith("_mag"):
            ax.axvspan(150.0, 161.0, color="tab:red", alpha=0.12, label="field disturbance")
        if scores:
            wins.append((min(scores, key=scores.get), short))
        ax.set_title(title, fontsize=10)
        ax.set_ylabel("deg")
        ax.set_xlim(left=0)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time (s)")
    # The title names, per filter, the panels where its RMS is the lowest.
    by_filter = defaultdict(list)
    for name, short in wins:
        by_filter[name].append(short)
    verdict = "Which filter? The lowest RMS error:\n" + "\n".join(
        f"{ahrs_label(name, '').split(' (')[0]}"
        f"{' (accel_stddev ' + name.rsplit('_', 1)[1] + ')' if name.startswith('engine') else ''}"
        f" on {', '.join(panels_won)}" for name, panels_won in by_filter.items())
    fig.suptitle(verdict, fontsize=11)
    # Room above the panels for the title's lines.
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.012 * (1 + len(by_filter))))
    fig.savefig(path, dpi=70)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------
# Which setting to pick: the cost of a step against the time a message spends in the node.
# ---------------------------------------------------------------------------------------------

def step_costs(medians):
    """The medians of one step of each method (kinematicStep/, dynamicStep/), by name."""
    return {n: v for n, v in medians.items()
            if n.split("/")[0] in ("kinematicStep", "dynamicStep")}


def node_latencies(node, mode):
    """Median latencies (ms) at the offered rates where `mode` keeps up: every rate up to there
    delivered (highest_lossless) and its p99 under 1 ms, i.e. no queue builds up."""
    top = highest_lossless(node, mode)
    return [num(r, "latency_p50_ms") for r in node
            if r["mode"] == mode and num(r, "rate_hz") <= top and num(r, "latency_p99_ms") < 1]


def advice_figures(medians, node):
    """(auto's kinematic step on the node's path [ns], the dearest step [name, ns], the node's
    median latencies [ms]) or None when a figure is missing."""
    steps = step_costs(medians)
    auto_path = medians.get("addSample/cf4")
    latencies = node_latencies(node, "node")
    if not steps or auto_path is None or not latencies:
        return None
    dearest = max(steps, key=steps.get)
    return auto_path, (dearest, steps[dearest]), latencies


def advice_title(medians, node):
    """The clause of the charts' titles that says why the cost of a method does not decide."""
    figures = advice_figures(medians, node)
    if figures is None:
        return ""
    auto_path, (_, dearest), latencies = figures
    return (f"its step costs {auto_path:.0f} ns (cf4 on the node's path; any method at most "
            f"{dearest:.0f} ns) against {min(latencies):.2f}-{max(latencies):.2f} ms for a "
            "message through the node")


def largest_saving(sweep):
    """The most CPU per simulated second (ns) another method saves over `auto`'s choice where it
    is cheaper to a tolerance of the sweep (auto_cells)."""
    savings = [work(mine) - work(best) for _, _, best, mine in auto_cells(sweep, SCENES)
               if mine is not None and mine is not best]
    return max(savings) if savings else 0.0


def advice_markdown(medians, node, sweep):
    """The paragraph that says which setting to pick, from the measurements."""
    figures = advice_figures(medians, node)
    if figures is None:
        return ("**Keep `integrator: auto`.** (No step costs or node latencies measured to "
                "compare.)")
    auto_path, (dearest_name, dearest), latencies = figures
    step = medians.get("kinematicStep/cf4")
    nodelet = node_latencies(node, "nodelet")
    nodelet_text = (f"; {min(nodelet):.2f}-{max(nodelet):.2f} ms as a nodelet" if nodelet
                    else "")
    saving = largest_saving(sweep)
    return (
        f"**Keep `integrator: auto`.** Its step in the kinematic model costs {auto_path:.0f} ns "
        f"on the node's path (`addSample/cf4`"
        f"{f', {step:.0f} ns for the step alone' if step else ''}), and the dearest step of any "
        f"method {dearest:.0f} ns (`{dearest_name}`), against a median of "
        f"{min(latencies):.2f}-{max(latencies):.2f} ms from `imu/data_raw` to `imu/data` "
        f"through the node at the rates it keeps up with{nodelet_text} (node benchmark below): "
        f"the integrator is {100 * auto_path / (1e6 * min(latencies)):.1g} % of a message's "
        "time with `auto` in the kinematic model and at most "
        f"{100 * dearest / (1e6 * min(latencies)):.1g} % with any "
        "method. So pick by the error, not the cost: the sections below measure `auto`'s "
        "choice against the cheapest method to each accuracy per scene and on the real "
        "streams, and where another method is cheaper it saves at most "
        f"{fmt(saving / 1e3, 2)} µs of CPU per simulated second.")


def main(argv):
    if len(argv) > 1 and argv[1] == "--fixes":
        fixes_chart(read_csv(os.path.join(argv[2], "fixes.csv")),
                    os.path.join(argv[3], "fixes.png"))
        return
    if len(argv) > 1 and argv[1] == "--ahrs":
        ahrs_chart(read_csv(os.path.join(argv[2], "ahrs.csv")), os.path.join(argv[3], "ahrs.png"))
        return
    data_dir, docs_dir = argv[1], argv[2]
    page = argv[3] if len(argv) > 3 else None
    sweep = read_csv(os.path.join(data_dir, "sweep.csv"))
    invariants = read_csv(os.path.join(data_dir, "invariants.csv"))
    assign_styles(sweep, invariants)
    costs_path = os.path.join(data_dir, "step_costs.json")
    medians = gbench_medians(costs_path) if os.path.exists(costs_path) else {}
    spreads = gbench_spreads(costs_path) if os.path.exists(costs_path) else {}
    node_path = os.path.join(data_dir, "node_bench.csv")
    node = aggregate_node(read_csv(node_path)) if os.path.exists(node_path) else []
    advice = advice_title(medians, node)
    work_precision_chart(sweep, os.path.join(docs_dir, "work_precision.png"), advice)
    order_chart(sweep, os.path.join(docs_dir, "order.png"))
    invariants_chart(invariants, os.path.join(docs_dir, "invariants.png"))
    stability_chart(read_csv(os.path.join(data_dir, "stability.csv")),
                    os.path.join(docs_dir, "stability.png"))
    streams_path = os.path.join(data_dir, "real_streams.csv")
    streams = read_csv(streams_path) if os.path.exists(streams_path) else []
    if streams:
        real_streams_chart(streams, os.path.join(docs_dir, "real_streams.png"), advice)
        streams_page = os.path.join(docs_dir, "real_streams.md")
        if os.path.exists(streams_page):
            splice_page(streams_page, settings_table(streams), docs_dir, "settings")
    fixes_path = os.path.join(data_dir, "fixes.csv")
    if os.path.exists(fixes_path):
        fixes_chart(read_csv(fixes_path), os.path.join(docs_dir, "fixes.png"))
    ahrs_path = os.path.join(data_dir, "ahrs.csv")
    if os.path.exists(ahrs_path):
        ahrs_chart(read_csv(ahrs_path), os.path.join(docs_dir, "ahrs.png"))
    if node:
        node_chart(node, os.path.join(docs_dir, "node_bench.png"))
    text = results_markdown(sweep, medians, node, bool(node), machine_line(data_dir), invariants,
                            spreads, streams)
    with open(os.path.join(docs_dir, "results.md"), "w") as f:
        f.write(charts_relative_to(text, docs_dir, docs_dir))  # results.md sits by the charts
    if page:
        splice_page(page, text, docs_dir)


if __name__ == "__main__":
    main(sys.argv)
