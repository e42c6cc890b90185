"""Write docs/benchmarks.md and its plots from benchmarks/results/<name>.json.

    python benchmarks/report.py [full|quick]
"""
from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
DOC = ROOT / "docs" / "benchmarks.md"
IMAGES = ROOT / "docs" / "images"

ORIGINAL = """The original C++ tool's times from the dissertation (Table 5.2, a different machine):
food delivery 394 s at 10 deliveries and out of memory at 20; vital signs 536 s at 2000 rooms;
pickup 966 s at 4000 pickups (its vital-signs and pickup worlds decompose nothing, see below)."""

PROFILE = """## Where the time goes

Profiled with cProfile on vital signs at 2000 and 5000 occupied rooms and on delivery at 5000
(the largest sizes), the work is spread over the pipeline; what dominated at first, and what was
done about it:

* **Constraint generation was quadratic.** The original generates, for a parallel operator, every
  pair of endpoints of its children's constraint lists, so the parallel node over the forAll
  instances produced O(n²) pairs that the transformation to decompositions then drops. They are
  now generated only when a sequential or fallback ancestor, or a context dependency, can use
  them (same result, `tests/test_conformance.py`). Vital signs, 1000 rooms: minutes → 3 s.
* **networkx and the cyclic garbage collector.** A vital-signs room yields 19 task instances that
  are pairwise execution-constrained: 0.8 million EC constraints at 5000 rooms. Building them as
  networkx edges and dataclasses, with Python's cyclic collector rescanning millions of live
  objects, cost more than everything else together. The Task Graph now keeps plain adjacency
  lists (networkx is not used there any more), constraints are named tuples, and the CLI disables
  the cyclic collector for its short life: 2.5-3x faster at 5000 rooms.
* **One CP-SAT model per forAll instance.** Components that are identical up to renaming (one per
  delivery or room) are solved once and their solutions renamed: delivery 5000, 9.4 s → 1.6 s
  for the space.
* **Output.** At 5000 rooms the output holds 95,000 task decompositions and 1 million
  constraints (330 MB of JSON in the original's layout); it is streamed with constraints
  formatted directly. What remains is proportional to the output size: expansion of the goal
  model (~10%), Task Graph (~25%), constraints (~25%), encoding and solving (~20%), writing (~20%).
* **Start-up, for small missions.** A whole run of a reference mission took 0.7 s, of which
  0.5 s were imports and table building: OR-Tools' high-level `cp_model` API pulls in pandas and
  numpy, and lark rebuilt its LALR tables on every run. Components are now built as model
  protos and solved through OR-Tools' lean `cp_model_helper`, loaded only when a component needs
  CP-SAT; tiny components (a few choices) are enumerated in Python instead, which the reference
  missions' all are; the parse tables are cached between runs. Room preparation: 0.70 s /
  111 MB → 0.23 s / 33 MB. What remains is mostly importing the package (about 0.1 s). The
  benchmarks compile the package's bytecode first, as a regular install has it: an editable
  install run with `PYTHONDONTWRITEBYTECODE` compiles every module on every run (0.08 s more).
  Alone, a reference mission takes 0.19–0.22 s here; the medians of the small-missions table
  (9 runs each) swing by up to 0.1 s with the machine's background load.
* **Coupled components.** Tasks that set, clear or test one shared fact made one component whose
  solutions were enumerated (1.2 × 10^15 for 19 parallel deliveries; coupled sequences took 51 s
  at n=16). The encoder now writes a fact's value as a chain, one step per writer, so that a
  component is a line of blocks passing a few state values: it is counted, listed, sampled and
  optimised over that layered graph (`solve/layered.py`) in time linear in the blocks.
* **Memory of execution constraints.** At 5000 rooms the Task Graph held every EC partner as its
  own record and every pair as a tuple, twice while trimming. Partners are shared, pairs are
  single ints, and the EC edges are walked on the untrimmed graph but added straight into the
  trimmed one: peak 1.02 GB → 0.88 GB. The objects a large mission has by the hundred thousand
  (vertices, decompositions, task instances, annotation-tree nodes, literals) then got slots, and
  the finished graph drops the set of EC pairs that only the construction rules need (it answers
  from the partner lists): 0.90 GB → 0.74 GB at 5000 rooms.
* **Output once per template.** The task entries of the forAll instances are equal up to renaming:
  each is formatted once per template (task, path, which parameter holds which value, and the
  values' sorts, which choose the attribute mappings) and filled with the instance's values
  (`output/entry_templates.py`; the same bytes, checked entry by entry on every reference mission, random
  missions and scaled worlds). Task entries at 5000 rooms: 2.1 s → 0.8 s.
* **Long sequences.** The tasks of a sequence of n see ever longer prefixes of a shared fact's
  writers; copying those into sets and walking the fact's chain from its start made the encoding
  cubic in practice (coupled-sequence n=10000: 128 s for the encoding alone). The decompositions a
  task sees are now runs of the depth-first vertex numbering (`semantics.Seen`), selected by
  bisection without copies, and a prefix's value is looked up by its length: 0.6 s.
* **Memory of large missions.** Vital signs at 5000 rooms peaked at 755 MB (50,000 rooms: 6.95 GB),
  the Task Graph build, the constraints, the encoding and the output each close to it. What held
  the memory, and what it is now: an index by vertex pair, a list per leaf and a tuple per edge in
  the Task Graph (adjacency lists by position, one dict per edge kind, the frozen graph reading one
  kind's successors from its list by kind); a set of every EC pair while building (the partner
  lists answer); a million constraint named tuples (`Constraints`, kept by column and read back as
  the same tuples); a set of partners per decomposition for robot preconditions (built on first
  use, one tuple per task); sets per vertex and per task pair while generating constraints; a
  recursive closure per goal in the expansion, a reference cycle the paused collector never freed;
  an equal robot-number record per task instance; the space section joined as one string before
  it was written. Peak 755 MB → 450 MB at 5000 rooms (13.0 s → 12.6 s), 6.95 GB → 4.04 GB at
  50,000 (176 s → 155 s), the same bytes. What remains is spread: the Task Graph (~80 MB at 5000
  rooms, twice while trimming), the expansion and its annotation tree (~65 MB), the space's
  solutions as frozensets (~50 MB).
* **Constraints by row.** Constraint generation appends a task pair's few decomposition pairs
  one by one (building columns to extend by cost more than the pairs), the implied-constraint
  pass and the output read the stored rows without making a tuple each, and the output makes the
  text around a constraint's two keys once per kind and flags: at 5000 rooms constraints 2.79 s
  → 2.05 s, output 2.29 s → 1.83 s, the same bytes.
* **Tree edges and robot numbers.** The Task Graph adds a tree edge with its new vertex in one
  step, without looking the pair up, and keeps no index of edge kinds by vertex pair (an edge is
  looked for among its source's successors; the rules that add many edges from one vertex know
  which are new); trimming 1.30 s → 1.06 s. Equal robot numbers are one record in the whole
  mission, so the million execution-constrained pairs that share one skip the check: 0.50 s →
  0.37 s. Whole run at 5000 rooms 12.2 s → 11.6 s (50,000 rooms: 129 s / 4024 MB → 127 s /
  3972 MB), the same bytes. Renumbering the kept vertices in place instead of copying them made
  trimming 0.5 s faster but the stages after it as much slower (the graph's vertices end up
  scattered in memory), and was dropped.
* **Stamping forAll copies.** Copies of a forAll that are identical up to renaming (the same
  goals and tasks, another room) are built once: the Task Graph is built, connected and
  trimmed with the first two copies, the last and the first of each shape, and every other
  copy is its representative's trimmed fragment with its own values, instances and grounded
  decompositions (`pipeline/stamping.py`, with the rules under which that is the same graph; the full
  construction runs otherwise); the constraints of a stamped copy are its source's, moved to
  its vertices. At 5000 rooms (one core) Task Graph 3.47 s → 1.95 s, constraints 2.0 s →
  0.18 s; whole run 11.6 s → 8.3 s, peak 437 MB → 418 MB (50,000 rooms: 127 s / 3972 MB →
  90 s / 3782 MB), the same bytes.
* **Stamped copies in the output; the output's head beside the solve.** A stamped copy's task
  entries are its source copy's with its own keys, ids and values: they are formatted once per
  source copy with a slot for each, and filled per copy with one string format
  (`output/copy_blocks.py`, with the rules under which that gives the same bytes): task entries at
  5000 rooms 1.19 s → 0.68 s. Most of the output (the actions, the task entries and the
  million constraints: 300 of its 330 MB) does not depend on the solver, so on two cores a
  forked child writes it to the output's temporary file while the parent encodes and solves;
  the parent then writes the decompositions and the space after it (`output/ahead.py`, from
  20,000 to 250,000 decompositions: the child copies the pages of the objects it reads, 410 +
  260 MB in all at 5000 rooms; at 50,000 rooms it would be 3.8 + 2.3 GB, where memory comes
  first). The stamped vertices are made from a recipe worked out once per source fragment, in
  one loop: Task Graph 1.75 s → 1.32 s. Whole run at 5000 rooms 8.2 s → 6.3 s (this machine,
  the same day), the same bytes. The peak memory measured is now the larger of one process's
  peak and the sampled total of the run's processes (`compare/measure.py`).
* **Fewer passes, and no teardown.** What was still done once per vertex and level, or per
  question, and what the end of a run cost: the parallel conflicts of every parallel operator
  (one per forAll copy, below the one over all copies) walked the operator's subtree; they are
  now read from each atom's writers, whose decompositions are a range of vertex numbers per
  operator (`semantics.ParallelConflicts`, checked against the walk on random missions). The
  finished Task Graph answered a task's decompositions by building a list from its AND
  successors, 200,000 times in the encoding; it keeps the lists (+9 MB at 5000 rooms). Record
  labels, with a precondition's repr, were formatted even when not explaining. A copied
  vertex's fields are set through their slots' descriptors; what every instance of a
  goal-model task shares is worked out at its first; a query that reads no variable is run
  once for all the elements of a forAll; components are found reading each record's
  variables once. Freeing the finished mission object by object took 0.25 s at 5000
  rooms: the console scripts keep it and end the process at once, after flushing the streams
  and running the exit handlers (`process.keep_until_exit`). Measured side by side on this
  machine at 5000 rooms (fresh output, 5 runs each): 6.05 s → 5.1 s (expansion 0.86 s →
  0.71 s, Task Graph 1.22 s → 1.04 s, encoding 1.52 s → 1.30 s, space 0.67 s → 0.60 s, one
  process); 50,000 rooms 70.6 s / 3810 MB (the previous report: 82.9 s / 3756 MB, on the
  machine it was made on). The same bytes.
* **Constraints by template, and the file written from a second thread.** At 50,000 rooms the
  output is 3.3 GB, two thirds of it eleven million constraints, and the output stage took a
  third of the run. A stamped copy's constraints were its source's moved one by one into the
  stored columns (2 s), then formatted one by one. The list now keeps such a run as its
  source's rows and a shift until something reads the rows (`Constraints.runs`; the output does
  not, and the counts by kind are read from the source's run), and the output makes one
  template per run, the text between the keys with a free place for each key, which every copy
  fills with its own keys in one join (`output/constraint_texts.py`). A stamped copy's task entries
  fill their source's text the same way: formatting it as a format string parsed its twenty
  kilobytes again for every copy. The kernel's share of writing 3.3 GB (3.3 s of `write` calls,
  copying into the page cache, more when the disk falls behind) no longer waits: where one
  process writes the whole output, a second thread writes the file in chunks of 8 MB while the
  text is formatted (`output/write_behind.py`; the `write` call releases the interpreter's lock;
  output stage 17.9 s → 13.9 s, measured in one process). Grounding a path without conditions
  or effects, and the effects of a decomposition without effects, give one shared frozen record
  (a third of vital signs' decompositions). Measured side by side on this machine (fresh
  output, two runs each, alternating): 50,000 rooms 62.5 s, 60.8 s / 3899 MB → 48.9 s, 49.8 s /
  3810 MB; 5000 rooms (three runs each) 4.59 s → 4.30 s (median). The same bytes (`cmp` at 5000
  rooms, MD5 at 50,000). The 50,000-room run varies with the machine's moment more than the
  small ones: over the day's runs of the same code it took 48.9–57.1 s (`large.py`: 51.9 s,
  then 55.8 s), the encoding's share varying most (12.8–16.0 s), and late in the day 64–67 s,
  when the earlier code took as long (64.4 s, 66.5 s, side by side); 5000 rooms took 4.3–4.9 s.
  The 60 s bound holds on this machine only at its quieter moments.
* **Replaying class leaders in the encoding.** The stamped copies of a forAll fall in few
  classes once the world is read too: of the 5000 rooms of the benchmark world, the 4997 stamped from the
  first room are 7 classes of copies whose atoms have, renamed, the same initial values,
  writers and chains. The encoder
  now encodes the first copy of each class in full and keeps its run of each phase (choices,
  task rules, checks) compiled into one function, which appends the run's variables, records
  and chains of values for another copy, given where that copy's variables start; the other
  copies call it (`solve/replay.py`). The class is one dictionary lookup: the first copy of a
  source fixes the templates (each atom its task rules read or its decompositions write, as
  the places of its arguments among the copy's parameter values), and a copy's key is what
  the world says of its templated atoms. Its achieve conditions are still read from its own
  vertices and compared. Variables are named by their parts, made into text only when read
  (`BoolModel.name`): the solver reads the names of the components it is handed, not of the
  million variables. The model is the full encoding's, variable for variable and record for
  record (`tests/test_encoding_replay.py`). Encoding at 50,000 rooms 17.3 s → 10.0 s (one
  process, the same moment). Measured side by side (fresh output, alternating): 5000 rooms
  4.84, 4.99, 5.00 s → 4.03, 4.25, 4.31 s; 50,000 rooms 66.9 s → 59.5 s, then 62.9 s → 54.7 s (at
  slow moments of the machine), 3823 → 3837 MB. `large.py`: 57.6 s, 57.1 s. The same bytes (`cmp`, MD5). A first version kept
  the encoder alive through a reference cycle (the collector is paused during a command):
  +800 MB at 50,000 rooms; the encoder now drops the replay when it is done. Another read a
  shared atom's writers once per copy before checking that they lie inside it: quadratic on
  the coupled family (10,000 deliveries 4.7 s → 27 s), caught by the benchmark table and fixed
  (5.4 s).
* **What is left.** At 50,000 rooms (py-spy, one run, at a slow moment: the same stages took
  about a fifth less the day before): loading and the initial state 1.7 s, expansion 7.7 s,
  Task Graph 13.1 s, encoding 9.1 s (its setup 2.3 s: effects, scopes, the mission queue),
  space 5.7 s, output 13.5 s. The output's 3.3 GB take the second thread 7–10 s of `write`
  calls (this disk takes 300–470 MB/s), so formatting it faster gains little. The space is
  still found record by record: a follower's component is its leader's renamed, which the
  replay could hand over instead (the next step). The expansion and the Task Graph still run
  per copy: a copy's queries read the world (each room's patients) before it is known to be a
  renaming of another, and grounding a copy's paths costs about as much as renaming its
  source's (tried and dropped: with one or two predicates per decomposition, building the
  renaming cost as much as grounding).
"""


def load(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text(encoding="utf-8"))


def fmt_time(row: dict | None) -> str:
    if row is None:
        return "—"
    if row["status"] == "timeout":
        return f"> {row.get('seconds', 0):.0f} s (limit)"
    if row["status"] != "ok":
        return row["status"]
    seconds = f"{row['seconds']:.3f}" if row["seconds"] < 0.1 else f"{row['seconds']:.2f}"  # start-up: to the ms
    return f"{seconds} s / {row['peak_mb']:.0f} MB"


def plots(rows: list[dict]) -> list[str]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: pip install matplotlib (plots skipped)", file=sys.stderr)
        return []
    IMAGES.mkdir(parents=True, exist_ok=True)
    series: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        if r["status"] == "ok" and not r["family"].startswith("dissertation") and r["family"] != "small":
            series[(r["family"], r["algorithm"])].append(r)
    names = []
    for metric, label, fname in (("seconds", "wall time (s)", "bench-time.png"),
                                 ("peak_mb", "peak memory (MB)", "bench-memory.png")):
        fig, ax = plt.subplots(figsize=(8, 5), dpi=110)
        for (family, algorithm), pts in sorted(series.items()):
            pts.sort(key=lambda r: r["n"])
            ax.plot([p["n"] for p in pts], [p[metric] for p in pts], marker="o",
                    linestyle="--" if algorithm == "exploratory" else "-", label=f"{family} / {algorithm}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("n (deliveries, pickups or occupied rooms)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        fig.savefig(IMAGES / fname)
        plt.close(fig)
        names.append(fname)
    return names


FAMILIES = ("delivery", "pickup", "vital-signs", "coupled", "coupled-sequence")


def targets(by: dict) -> list[str]:
    def get(family: str, n: int, algorithm: str) -> dict | None:
        return by.get((family, n, algorithm))

    lines = ["| target | bound | measured | met |", "|---|---|---|---|"]

    def add(name: str, bound: str, row: dict | None, ok) -> None:
        measured = fmt_time(row)
        met = "—" if row is None or row["status"] != "ok" else ("yes" if ok(row) else "**no**")
        lines.append(f"| {name} | {bound} | {measured} | {met} |")

    add("delivery n=10, all 59,049 decompositions written (`--limit 0`)", "< 5 s",
        get("delivery", 10, "cpsat-all"), lambda r: r["seconds"] < 5)
    add("food delivery n=9, all 19,683 decompositions written (`--limit 0`)", "≤ 0.35 s",
        get("delivery", 9, "cpsat-all"), lambda r: r["seconds"] <= 0.35)
    add("delivery n=5000: exact count + first 1000 decompositions", "< 10 s, < 2 GB",
        get("delivery", 5000, "cpsat"), lambda r: r["seconds"] < 10 and r["peak_mb"] < 2048)
    add("delivery n=5000: optimum (fewest actions)", "< 10 s, < 2 GB",
        get("delivery", 5000, "cpsat-optimize"), lambda r: r["seconds"] < 10 and r["peak_mb"] < 2048)
    add("vital signs, 5000 occupied rooms x 2 patients", "< 30 s",
        get("vital-signs", 5000, "cpsat"), lambda r: r["seconds"] < 30)
    add("vital signs, 5000 occupied rooms, `--limit 1`", "≤ 5 s, ≤ 800 MB",
        get("vital-signs", 5000, "cpsat"), lambda r: r["seconds"] <= 5 and r["peak_mb"] <= 800)
    large = get("vital-signs", 50_000, "cpsat")
    add("vital signs, 50,000 occupied rooms, `--limit 1` (`benchmarks/large.py`, one run"
        + (f", {large['output_mb'] / 1024:.1f} GB of output streamed" if large and "output_mb" in large else "") + ")",
        "≤ 60 s, ≤ 4 GB, streamed", large, lambda r: r["seconds"] <= 60 and r["peak_mb"] <= 4096)
    add("coupled deliveries n=19, `count`", "≤ 0.5 s", get("coupled", 19, "count"), lambda r: r["seconds"] <= 0.5)
    add("coupled deliveries n=1000, `count`", "≤ 5 s", get("coupled", 1000, "count"), lambda r: r["seconds"] <= 5)
    add("coupled deliveries n=1000, `--optimize`", "≤ 5 s", get("coupled", 1000, "cpsat-optimize"),
        lambda r: r["seconds"] <= 5)
    add("coupled sequence n=19, `count`", "≤ 0.5 s", get("coupled-sequence", 19, "count"),
        lambda r: r["seconds"] <= 0.5)
    add("coupled sequence n=1000, `count`", "≤ 5 s", get("coupled-sequence", 1000, "count"),
        lambda r: r["seconds"] <= 5)
    add("coupled sequence n=1000, `--optimize`", "≤ 5 s", get("coupled-sequence", 1000, "cpsat-optimize"),
        lambda r: r["seconds"] <= 5)
    small = [r for r in by.values() if r["family"] == "small" and r["algorithm"] != "floor" and r["status"] == "ok"]
    if small:
        slowest = max(small, key=lambda r: r["seconds"])
        add(f"every reference mission, whole process (slowest: {slowest['mission']}, {slowest['algorithm']})",
            "≤ 0.25 s", slowest, lambda r: r["seconds"] <= 0.25)
    for family in FAMILIES:
        algorithm = "count" if family.startswith("coupled") else "cpsat"
        a, b = get(family, 500, algorithm), get(family, 5000, algorithm)
        if a and b and a["status"] == b["status"] == "ok":
            ratio = b["seconds"] / a["seconds"]
            lines.append(f"| {family}: time(5000) / time(500), {algorithm} (linear: 10) | ≤ 12 | {ratio:.1f} | "
                         f"{'yes' if ratio <= 12 else '**no**'} |")
    return lines


def ratio_to_original(ours: dict | None, original: dict | None) -> float | None:
    """Our time over the original's, both measured in the same run; None where either failed."""
    if not ours or not original or ours["status"] != "ok" or original["status"] != "ok" or not original["seconds"]:
        return None
    return ours["seconds"] / original["seconds"]


def fmt_ratio(ratio: float | None) -> str:
    return "—" if ratio is None else f"{ratio:.1f}×"


def small_missions(rows: list[dict]) -> list[str]:
    """The reference missions run whole, beside the floor (starting Python) and the original."""
    small = [r for r in rows if r["family"] == "small"]
    floor = next((r for r in small if r["algorithm"] == "floor"), None)
    if not small or floor is None:
        return []
    out = ["## Small missions", "",
           "Every mission and configuration of the reference corpus, decomposed as a user runs it: one "
           "`mutrose-cp decompose` process each, start-up included, beside the original tool given the same "
           "mission in the same run (where it is installed: `../shared/original`, or `MUTROSE_ORIGINAL`). The "
           f"floor is starting Python (`python -c pass`): {floor['seconds']:.3f} s, {floor['peak_mb']:.0f} MB.", "",
           "| mission / configuration | exploratory | cpsat | original | cpsat / original | cpsat / floor |",
           "|---|---|---|---|---|---|"]
    by = {(r["mission"], r["algorithm"]): r for r in small}
    for mission in sorted({r["mission"] for r in small if r["algorithm"] != "floor"}):
        e, c, o = (by.get((mission, a)) for a in ("exploratory", "cpsat", "original"))
        ratio = f"{c['seconds'] / floor['seconds']:.0f}×" if c and c.get("seconds") and floor["seconds"] else "—"
        out.append(f"| {mission} | {fmt_time(e)} | {fmt_time(c)} | {fmt_time(o)} | "
                   f"{fmt_ratio(ratio_to_original(c, o))} | {ratio} |")
    return out + [""]


def plugin_calls(rows: list[dict]) -> list[str]:
    """The editor plug-in's call, ``mutrose HDDL GM CONFIG -p``, beside the original's."""
    calls = [r for r in rows if r["family"] == "plugin"]
    if not calls:
        return []
    out = ["## The editor plug-in's call", "",
           "`mutrose HDDL GM CONFIG -p`, as mutrose-vscode runs it on every edit, inside a copy of each mission "
           "folder whose `-p` output the corpus records (`reference/console`), beside the original given the same "
           "command line in the same run.", "",
           "| mission / configuration | mutrose -p | original -p | mutrose / original |", "|---|---|---|---|"]
    by = {(r["mission"], r["algorithm"]): r for r in calls}
    for mission in sorted({r["mission"] for r in calls}):
        ours, theirs = by.get((mission, "mutrose -p")), by.get((mission, "original -p"))
        out.append(f"| {mission} | {fmt_time(ours)} | {fmt_time(theirs)} | "
                   f"{fmt_ratio(ratio_to_original(ours, theirs))} |")
    return out + [""]


def start_up_targets(by: dict) -> list[str]:
    """Whole process on every reference mission within twice the original's time, side by side."""
    lines = []
    for family, ours_label, theirs_label, what in (("small", "cpsat", "original", "`mutrose-cp decompose`"),
                                                  ("plugin", "mutrose -p", "original -p", "`mutrose -p`")):
        rows = [r for r in by.values() if r["family"] == family]
        pairs = {}
        for r in rows:
            pairs.setdefault(r.get("mission"), {})[r["algorithm"]] = r
        ratios = [(ratio_to_original(p.get(ours_label), p.get(theirs_label)), mission) for mission, p in pairs.items()
                  if theirs_label in p]
        measured = [(x, m) for x, m in ratios if x is not None]
        if not measured:
            continue
        worst, mission = max(measured)
        met = "yes" if worst <= 2 and len(measured) == len(ratios) else "**no**"
        lines.append(f"| every reference mission, whole process, {what} / the original (worst: {mission}) | ≤ 2× | "
                     f"{worst:.1f}× | {met} |")
    return lines


def main(argv: list[str]) -> int:
    name = argv[0] if argv else "full"
    data = load(name)
    rows = data["rows"]
    by = {(r["family"], r["n"], r["algorithm"]): r for r in rows}
    if name == "full" and (RESULTS / "small.json").exists():  # run.py --small-only: the start-up rows, rerun
        small = load("small")
        rows = [r for r in rows if r["family"] not in ("small", "plugin")] + small["rows"]
        by = {(r["family"], r["n"], r["algorithm"]): r for r in rows}
    if (RESULTS / "large.json").exists():  # benchmarks/large.py: one run of the largest mission
        by.update({(r["family"], r["n"], r["algorithm"]): r for r in load("large")["rows"]})
    m = data["machine"]
    out = ["# Benchmarks", "",
           f"Generated by `python benchmarks/run.py{' --quick' if name == 'quick' else ''}` (or, from "
           f"recorded results, `python benchmarks/report.py {name}`) on {data['date']}. Machine: {m.get('cpu', '?')}, "
           f"{m.get('cpus')} cores, {m.get('memory_gb')} GB, Python {m.get('python')}. Each entry is the median "
           f"of {data['repeats']} runs, each a separate process whose wall time and peak resident memory are "
           f"measured by its parent; per-run limit {data['timeout_s']:.0f} s (an algorithm's ladder stops at "
           f"its first failure). Run time of the whole benchmark: {data['elapsed_s']:.0f} s.", "",
           "Families (generated by `benchmarks/generate.py` on the reference missions' domains and goal models):",
           "",
           "* **delivery**: food-logistics delivery, n deliveries, every patient able to fetch: three "
           "alternatives per delivery, 3^n valid mission decompositions;",
           "* **pickup**: food-logistics pickup, n pickups, every patient able to open the door;",
           "* **vital-signs**: n occupied rooms with two patients each, conditions varied (19 task instances "
           "and ~200 constraints per room);",
           "* **coupled**: delivery where every GetFood may also mark the shared kitchen busy or free, so the "
           "parallel deliveries conflict through one fact: 3^n (2^(n+1) - 1) decompositions in one coupled "
           "component of 2^(n+1) - 1 solutions. It is solved block by block as a layered graph "
           "(`solve/layered.py`: the conflict passes from delivery to delivery as \"set so far\" and "
           "\"cleared so far\"), so `count` and `--optimize` need no enumeration;",
           "* **coupled-sequence**: n GetFood tasks in one sequence (a goal model of its own) that mark the kitchen "
           "busy (only when it is free), free it, or pick up without marking (only when it is free): one component "
           "of about 2.414^n solutions whose tasks share the kitchen's state. It is solved block by block as a "
           "layered graph (`solve/layered.py`): counted, listed lazily, sampled and optimised without enumeration, "
           "and written as that graph.", "",
           "Measured commands: `exploratory` = `decompose --algorithm exploratory` (lists every decomposition); "
           "`cpsat` = `decompose` (exact count, decomposition space and the first 1000 decompositions; for vital "
           "signs `--limit 1`, since each decomposition lists 19 n keys); `cpsat-all` = `decompose --limit 0`; "
           "`cpsat-optimize` = `decompose --optimize`.", "",
           "The exploratory algorithm keeps every decomposition in memory, so its ladder is capped where that "
           "list no longer fits: n ≤ 12 for delivery (3^12 = 531,441 decompositions, 1.4 GB) and n ≤ 10 for "
           "pickup (4^10, 3.2 GB); for vital signs it stops at the time limit. `cpsat-all` (writing every "
           "decomposition) is run up to n = 10.", "", ORIGINAL, "", "## Targets", ""]
    out += targets(by)
    out += start_up_targets(by)
    out += ["", "## Results", ""]
    for family in FAMILIES:
        algos = [a for a in ("exploratory", "cpsat", "count", "cpsat-all", "cpsat-optimize", "original")
                 if any(k[0] == family and k[2] == a for k in by)]
        sizes = sorted({k[1] for k in by if k[0] == family})
        if not sizes:
            continue
        out += [f"### {family}", "", "| n | task instances | decompositions | " + " | ".join(algos)
                + " | exploratory / cpsat |", "|---" * (len(algos) + 4) + "|"]
        for n in sizes:
            any_row = next((by[(family, n, a)] for a in algos if (family, n, a) in by and by[(family, n, a)].get("task_instances") is not None), None)
            e, c = by.get((family, n, "exploratory")), by.get((family, n, "cpsat"))
            ratio = (f"{e['seconds'] / c['seconds']:.2f}" if e and c and e["status"] == c["status"] == "ok" else "—")
            out.append(f"| {n} | {any_row.get('task_instances') if any_row else '—'} | "
                       f"{any_row.get('mission_decompositions') if any_row else '—'} | "
                       + " | ".join(fmt_time(by.get((family, n, a))) for a in algos) + f" | {ratio} |")
        out.append("")
    out += small_missions(rows)
    out += plugin_calls(rows)
    diss = [r for r in rows if r["family"].startswith("dissertation")]
    if diss:
        out += ["## The dissertation's own worlds", "",
                "The worlds of `reference/scalability`. In its vital-signs and pickup worlds no room is occupied and "
                "no pickup requested, so those runs decompose nothing (0 task instances): they only time reading and "
                "querying the world. The delivery worlds do decompose. All are read with `--lenient-xml`: the "
                "delivery world with n = 12 (`world_db5.xml`) leaves `Location12` unclosed, and the original's "
                "reading nests every patient inside it.", "",
                "| world | n | task instances | decompositions | exploratory | cpsat |", "|---|---|---|---|---|---|"]
        dby = {(r["family"], r["n"], r["algorithm"]): r for r in diss}
        for fam, n in sorted({(r["family"], r["n"]) for r in diss}, key=lambda k: (k[0], k[1])):
            e, c = dby.get((fam, n, "exploratory")), dby.get((fam, n, "cpsat"))
            ref = c or e
            out.append(f"| {fam.removeprefix('dissertation-')} | {n} | {ref.get('task_instances')} | "
                       f"{ref.get('mission_decompositions')} | {fmt_time(e)} | {fmt_time(c)} |")
        out.append("")
    images = plots(rows)
    if images:
        out += ["## Plots", ""] + [f"![{i}](images/{i})" for i in images] + [""]
    if (RESULTS / "allocation.json").exists():  # recorded by benchmarks/allocation.py, its own report
        out += ["## Allocation", "", "`mutrose-cp allocate` (decomposition, robots and schedule with travel) on "
                "deliveries on a grid, 5 to 50 robots: [its own report](benchmarks-allocation.md).", ""]
    out += [PROFILE]
    DOC.write_text("\n".join(out), encoding="utf-8")
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
