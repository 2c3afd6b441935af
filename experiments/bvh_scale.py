"""The BVH against Embree across scales (issue 32), from a runs CSV of `raylab sweep --plan
data/plans/bvh_scale.json`: per scene, structure and ray kind, Embree's ns/ray over ours (> 1: ours is
faster) in each measurement of the case (the first and its replicates), the median over them with a 95%
percentile-bootstrap interval; and the geometric mean over the scenes, taken measurement by measurement.
Writes OUT/README.md (tables, the command, the goals) and OUT/bvh_scale.png.

With BENCH_JSONs, Google Benchmark JSONs of `bench_bvh` on larger scenes (RAYLAB_BENCH_BVH_SCENES, with
--benchmark_repetitions), the page also gives those scenes' ratios to Embree's fast mode (`vs_embree_fast`),
median over the repetitions [95%], and bytes per triangle where recorded; JSONs of `bench_bvh_build`
(RAYLAB_BENCH_BVH_BUILD_SCENES and _SPECS) give build times against Embree's and issue 32's build goals.

A runs CSV holds one thread count: with 1 the goals are issue 32's single-thread ones, with more its
2-thread ones (robust=off ≥ 1.1, the default ≥ 1.0), and times are wall clock. --plan names the plan
the page's command gives (default data/plans/bvh_scale.json). A single-thread page links the pages of
OUT_DIR/threadsN/.

Usage: python3 experiments/bvh_scale.py RUNS_CSV OUT_DIR [BENCH_JSON...] [--plan PLAN]"""
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

RESAMPLES = 2000
SEED = 20261204
KINDS = ["primary", "diffuse", "shadow"]
GOALS = {"bvh:robust=off": 1.2, "bvh": 1.0}  # issue 32: against `embree` (fast mode), every kind and scale
GOALS_MULTITHREAD = {"bvh:robust=off": 1.1, "bvh": 1.0}  # issue 32: the same on 2 threads


def median_interval(values):
    """The median of `values` and its 95% percentile-bootstrap interval (RESAMPLES, fixed seed)."""
    v = np.asarray(values, dtype=float)
    rng = np.random.default_rng(SEED)
    medians = np.median(rng.choice(v, size=(RESAMPLES, len(v)), replace=True), axis=1)
    return float(np.median(v)), float(np.quantile(medians, 0.025)), float(np.quantile(medians, 0.975))


BYTES_GOAL = 0.5  # issue 32: bytes per triangle at most half Embree's
# Variants whose time is compared with the structure they change: (the parameter, what it changes).
TWINS = [("nodes=quantized", "quantized nodes against full nodes"),
         ("leaves=indexed", "indexed leaves against packed leaves")]


def twin(accel: str, param: str) -> str:
    """The spec of `accel` with `param` first among its parameters (`bvh`, nodes=quantized ->
    `bvh:nodes=quantized`; `bvh:nodes=quantized`, leaves=indexed -> `bvh:leaves=indexed,nodes=quantized`)."""
    kind, _, params = accel.partition(":")
    return f"{kind}:{param}" + (f",{params}" if params else "")


def memory_section(df: pd.DataFrame) -> list:
    """Bytes per triangle (ours and, where the runs record it, Embree's) and node visits per structure and
    scene, the bytes goal per structure, and, for every structure whose twin (TWINS) is in the data, the
    twin's time against it: the ratio of their Embree ratios, measurement by measurement (both alternate
    with Embree on the same rays), median [95%]."""
    if not {"bytes", "nodes_per_ray", "leaves_per_ray"} <= set(df.columns):
        return []
    embree = "embree_bytes" in df.columns and bool((df["embree_bytes"] > 0).all())
    md = ["", "## Memory and node visits", "",
          "*bytes/tri*: the traversed structure per triangle: wide nodes and leaf packets, and with indexed leaves "
          "the mesh vertices they read; *visits/ray*: interior nodes + leaves per diffuse ray; *ns/visit*: diffuse "
          "ns/ray over visits/ray (the traversal's time per visit, leaf tests included)."
          + (" *Embree bytes/tri*: the Embree scene each row was timed against, its BVH and its geometry buffers "
             "(Embree's memory monitor), median over the measurements." if embree else ""), "",
          "| scene | triangles | structure | bytes/tri | " + ("Embree bytes/tri | / Embree | " if embree else "") +
          "visits/ray | ns/visit |", "|---|---|---|---|" + ("---|---|" if embree else "") + "---|---|"]
    diffuse = df[df["ray_kind"] == "diffuse"]
    worst = {}
    for (scene, accel), g in sorted(diffuse.groupby(["scene", "accel"]), key=lambda k: (k[1]["primitives"].iloc[0], k[0][1])):
        tris = int(g["primitives"].iloc[0])
        visits = float(np.median(g["nodes_per_ray"] + g["leaves_per_ray"]))
        ns = float(np.median(g["ns_per_ray_min"]))
        ours = float(np.median(g["bytes"])) / tris
        cells = f"| {scene} | {tris:.3g} | `{accel}` | {ours:.1f} | "
        if embree:
            theirs = float(np.median(g["embree_bytes"])) / tris
            worst.setdefault(accel, []).append((ours / theirs, scene))
            cells += f"{theirs:.1f} | {ours / theirs:.2f} | "
        md.append(cells + f"{visits:.1f} | {ns / visits:.1f} |")
    if worst:
        md += ["", f"Bytes per triangle against Embree's (issue 32's goal: ≤ {BYTES_GOAL}×; a count, no interval), "
               "the highest over the scenes:", "",
               "| structure | highest / Embree | at | goal met? |", "|---|---|---|---|"]
        for accel, ratios in worst.items():
            r, scene = max(ratios)
            md.append(f"| `{accel}` | {r:.2f} | {scene} | {'yes' if r <= BYTES_GOAL else 'no'} |")
    accels = set(df["accel"])
    for param, title in TWINS:
        pairs = [(a, twin(a, param)) for a in dict.fromkeys(df["accel"]) if param not in a and twin(a, param) in accels]
        if not pairs:
            continue
        name = param.split("=")[1]
        md += ["", f"### {title[0].upper() + title[1:]}", "",
               f"Throughput of the {name} twin over the structure it changes (> 1: the twin is faster), from their "
               "ratios to Embree measurement by measurement, median [95%].", "",
               f"| scene | triangles | comparison | primary | diffuse | shadow | bytes/tri, twin / structure |",
               "|---|---|---|---|---|---|---|"]
        for base, variant in pairs:
            for scene, g in sorted(df.groupby("scene"), key=lambda k: k[1]["primitives"].iloc[0]):
                cells = []
                for kind in KINDS:
                    a = g[(g["accel"] == base) & (g["ray_kind"] == kind)].set_index("replicate")["ratio"]
                    b = g[(g["accel"] == variant) & (g["ray_kind"] == kind)].set_index("replicate")["ratio"]
                    both = (b / a).dropna()
                    if both.empty:
                        cells.append("–")
                        continue
                    m, lo, hi = median_interval(both)
                    cells.append(f"{m:.2f} [{lo:.2f}, {hi:.2f}]")
                bytes_base = float(np.median(g[g["accel"] == base]["bytes"]))
                bytes_variant = float(np.median(g[g["accel"] == variant]["bytes"]))
                md.append(f"| {scene} | {int(g['primitives'].iloc[0]):.3g} | `{variant}` / `{base}` | " +
                          " | ".join(cells) + f" | {bytes_variant / bytes_base:.2f} |")
    return md


def grouped_runs(bench_jsons: list, names: tuple, case, command):
    """The iteration runs of `bench_jsons` whose benchmark (the name's first part) is one of `names`,
    grouped by case(run); a case in several JSONs pools their repetitions, and each run's `_rep` (its
    JSON and repetition) pairs one process's repetitions. Also, for each JSON holding such runs,
    command(JSON, its groups): the command that measured it."""
    groups, commands = {}, []
    for bench_json in bench_jsons:
        mine = {}
        for b in json.loads(pathlib.Path(bench_json).read_text())["benchmarks"]:
            if b.get("run_type", "iteration") != "iteration" or b["name"].split("/")[0] not in names:
                continue
            b["_rep"] = (bench_json, b.get("repetition_index", 0))
            mine.setdefault(case(b), []).append(b)
        if not mine:
            continue
        commands.append(command(bench_json, mine))
        for key, g in mine.items():
            groups.setdefault(key, []).extend(g)
    return groups, commands


def bench_command(binary: str, variable: str, scenes: list, specs: list, bench_json: str, mine: dict) -> str:
    """The command that wrote `bench_json`: `binary` on `scenes` and `specs` (each once, in order) through
    $`variable`_SCENES and _SPECS, with as many repetitions as its largest group in `mine`."""
    return (f"{variable}_SCENES='{';'.join(dict.fromkeys(scenes))}' {variable}_SPECS='{';'.join(dict.fromkeys(specs))}' "
            f"build/experiments/{binary} --benchmark_repetitions={max(len(g) for g in mine.values())} "
            f"--benchmark_out={bench_json} --benchmark_out_format=json")


def measured_by(title: str, commands: list, method: str) -> list:
    """A section's title, the commands that measured its JSONs, and how: `method`."""
    return (["", title, ""] + [f"`{cmd}`" for cmd in commands] +
            ["", "then this script with " + ("that JSON" if len(commands) == 1 else "those JSONs") + " as BENCH_JSON. " +
             method])


def bench_section(bench_jsons: list) -> list:
    """The table of bench_bvh's repetitions, over every JSON of `bench_jsons`: per scene, structure and
    ray kind, vs_embree_fast (Embree's fast mode over ours, each the best of 5 alternated passes) median
    [95%] over the repetitions (of every JSON that measures the case), nodes/ray, and (where the JSON
    records them) bytes per triangle, ours and over Embree's."""
    def case(b):  # BM_BvhTrace / scene / rays / spec / iterations:N; scene specs hold no '/', a spec may
        parts = b["name"].split("/")
        return parts[1], parts[2].split(":")[0], "/".join(parts[3:-1])

    def command(bench_json, mine):
        return bench_command("bench_bvh", "RAYLAB_BENCH_BVH", [k[0] for k in mine], [k[2] for k in mine], bench_json,
                             mine)

    groups, commands = grouped_runs(bench_jsons, ("BM_BvhTrace",), case, command)
    if not groups:
        return []
    md = measured_by("## Scenes beyond the sweep (bench_bvh)", commands,
                     "Each repetition builds every structure again and keeps the best of 5 passes alternating ours, "
                     "`embree-robust` and `embree` on the same 65,536 rays (thread CPU time); *ratio* is `embree`'s time "
                     "over ours, median over the repetitions [95% bootstrap]; *bytes/tri* ours, and over Embree's "
                     "fast-mode scene (its BVH and geometry buffers), where the run recorded them.")
    md += ["", "| scene | triangles | structure | rays | ratio to `embree` [95%] | repetitions | nodes/ray | bytes/tri | "
           "/ Embree's |", "|---|---|---|---|---|---|---|---|---|"]
    for (scene, kind, spec), g in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][2], KINDS.index(kv[0][1]) if kv[0][1] in KINDS else 9)):
        m, lo, hi = median_interval([b["vs_embree_fast"] for b in g])
        tris = f"{g[0]['triangles']:.3g}" if "triangles" in g[0] else "–"
        memory = "– | –"
        if "bytes_per_tri" in g[0] and "embree_bytes_per_tri" in g[0]:
            ours, theirs = (float(np.median([b[k] for b in g])) for k in ("bytes_per_tri", "embree_bytes_per_tri"))
            memory = f"{ours:.1f} | {ours / theirs:.2f}"
        md.append(f"| {scene} | {tris} | `{spec}` | {kind} | {m:.2f} [{lo:.2f}, {hi:.2f}] | {len(g)} | "
                  f"{float(np.median([b['nodes'] for b in g])):.1f} | {memory} |")
    return md + kernel_section(groups)


# The default's time against the specs that drop, in turn, the certified kernel and the conservative traversal.
KERNEL_STEPS = ("bvh", "bvh:kernel=watertight", "bvh:robust=off")


def kernel_section(groups: dict) -> list:
    """Where the default `bvh` loses time, from bench_bvh runs of the three KERNEL_STEPS on the same scene
    and rays: the certified kernel against the watertight one (both under the conservative traversal), and
    that against `robust=off` (Möller-Trumbore and the plain slab test). Each time ratio is the ratio of the
    two specs' throughputs over Embree's fast mode, repetition by repetition of one process, median [95%]."""
    cases = sorted({(scene, kind) for scene, kind, spec in groups
                    if all((scene, kind, s) in groups for s in KERNEL_STEPS)},
                   key=lambda k: (k[0], KINDS.index(k[1]) if k[1] in KINDS else 9))
    if not cases:
        return []
    md = ["", "### Where the default's time goes", "",
          "Time per ray of the default `bvh` (certified kernel, conservative traversal) over `bvh:kernel=watertight` "
          "(watertight kernel, the same traversal), and of that over `bvh:robust=off` (Möller-Trumbore, plain slab "
          "test): each from the two structures' throughputs over Embree's fast mode, repetition by repetition "
          "(> 1: the first is slower), median [95%]; the three trace the same trees (nodes and tests per ray).", "",
          "| scene | triangles | rays | certified / watertight [95%] | watertight / `robust=off` [95%] | "
          "default / `robust=off` [95%] | nodes/ray | tests/ray |", "|---|---|---|---|---|---|---|---|"]

    def time_ratio(scene, kind, slow, fast):
        by_rep = {spec: {b["_rep"]: b["vs_embree_fast"] for b in groups[(scene, kind, spec)]} for spec in (slow, fast)}
        both = [by_rep[fast][r] / by_rep[slow][r] for r in by_rep[slow] if r in by_rep[fast]]
        m, lo, hi = median_interval(both)
        return f"{m:.2f} [{lo:.2f}, {hi:.2f}]"

    for scene, kind in cases:
        g = groups[(scene, kind, "bvh")]
        tris = f"{g[0]['triangles']:.3g}" if "triangles" in g[0] else "–"
        md.append(f"| {scene} | {tris} | {kind} | {time_ratio(scene, kind, 'bvh', 'bvh:kernel=watertight')} | "
                  f"{time_ratio(scene, kind, 'bvh:kernel=watertight', 'bvh:robust=off')} | "
                  f"{time_ratio(scene, kind, 'bvh', 'bvh:robust=off')} | {float(np.median([b['nodes'] for b in g])):.1f} | "
                  f"{float(np.median([b['tests'] for b in g])):.1f} |")
    return md


BUILD_GOALS = {"plain": 1.0, "optimized": 1.5}  # issue 32: build (+ optimise) over Embree medium, at 10^6


def build_section(bench_jsons: list) -> list:
    """The table of bench_bvh_build's repetitions, over every JSON of `bench_jsons` that holds
    BM_BvhBuild or BM_SbvhBuild runs: per scene, spec and threads, our best build wall time over
    Embree's (medium quality; high for the SBVH), median over the repetitions [95%], and issue 32's
    goal for it: plain `bvh` ≤ 1.0, a spec with optimize= (build + optimise) ≤ 1.5. A goal is met when
    the whole interval is at most the goal, missed when none of it is."""
    def case(b):  # name / scene / threads [/ spec] / iterations:N; scene specs hold no '/', a spec may
        parts = b["name"].split("/")
        spec = "bvh:builder=spatial" if parts[0] == "BM_SbvhBuild" else ("/".join(parts[3:-1]) or "bvh")
        return parts[1], spec, int(parts[2])

    def command(bench_json, mine):
        return bench_command("bench_bvh_build", "RAYLAB_BENCH_BVH_BUILD", [k[0] for k in mine],
                             [k[1] for k in mine if k[1] != "bvh:builder=spatial"], bench_json, mine)

    groups, commands = grouped_runs(bench_jsons, ("BM_BvhBuild", "BM_SbvhBuild"), case, command)
    if not groups:
        return []
    md = measured_by("## Build time against Embree (bench_bvh_build)", commands,
                     "Each repetition builds ours and Embree's in turn 7 times (5 for the SBVH), each in a TBB arena of "
                     "the stated threads, and keeps each one's best wall time; *ours / Embree* is their ratio (< 1: ours "
                     "builds faster), median over the repetitions [95% bootstrap]. Against Embree medium quality, the "
                     "SBVH against Embree high. *SAH / plain*: the tree's SAH cost over plain `bvh`'s on the same scene. "
                     f"Issue 32's goals at 10^6 triangles: plain binned `bvh` ≤ {BUILD_GOALS['plain']}, build + optimise "
                     f"≤ {BUILD_GOALS['optimized']}; met when the whole interval is within the goal.")
    md += ["", "| scene | triangles | structure | threads | ours ms | Embree ms | ours / Embree [95%] | repetitions | "
           "SAH / plain | goal | met? |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for (scene, spec, threads), g in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][2], kv[0][1])):
        m, lo, hi = median_interval([b["vs_embree"] for b in g])
        tris = f"{g[0]['triangles']:.3g}" if "triangles" in g[0] else "–"
        plain = groups.get((scene, "bvh", threads))
        sah = (f"{float(np.median([b['sah_cost'] for b in g])) / float(np.median([b['sah_cost'] for b in plain])):.3f}"
               if plain and "sah_cost" in g[0] else "–")
        goal = BUILD_GOALS["optimized"] if "optimize=" in spec else BUILD_GOALS["plain"] if spec == "bvh" else None
        met = "–" if goal is None else "yes" if hi <= goal else "no" if lo > goal else "not shown at this noise"
        md.append(f"| {scene} | {tris} | `{spec}` | {threads} | {float(np.median([b['ours_ms'] for b in g])):.0f} | "
                  f"{float(np.median([b['embree_ms'] for b in g])):.0f} | {m:.2f} [{lo:.2f}, {hi:.2f}] | {len(g)} | "
                  f"{sah} | {'≤ ' + format(goal, '.1f') if goal else '–'} | {met} |")
    return md


def main(runs_csv: str, out_dir: str, *bench_jsons: str, plan: str = "data/plans/bvh_scale.json") -> int:
    bench_md = []
    for bench_json in bench_jsons:
        try:
            names = [b["name"].split("/")[0] for b in json.loads(pathlib.Path(bench_json).read_text())["benchmarks"]]
            if not {"BM_BvhTrace", "BM_BvhBuild", "BM_SbvhBuild"} & set(names):
                raise ValueError("no BM_BvhTrace, BM_BvhBuild or BM_SbvhBuild runs")
        except (OSError, ValueError, KeyError, TypeError, AttributeError, json.JSONDecodeError) as e:
            print(f"bvh_scale: {bench_json}: not a bench_bvh or bench_bvh_build JSON ({e})", file=sys.stderr)
            return 2
    if bench_jsons:
        try:
            bench_md = bench_section(list(bench_jsons)) + build_section(list(bench_jsons))
        except (OSError, ValueError, KeyError, IndexError, json.JSONDecodeError) as e:
            print(f"bvh_scale: {' '.join(bench_jsons)}: not bench_bvh or bench_bvh_build JSONs ({e})", file=sys.stderr)
            return 2
    if not pathlib.Path(runs_csv).is_file():
        print(f"bvh_scale: {runs_csv}: no such file", file=sys.stderr)
        return 2
    try:
        df = pd.read_csv(runs_csv)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        print(f"bvh_scale: {runs_csv}: not a CSV file ({e})", file=sys.stderr)
        return 2
    missing = {"scene", "accel", "ray_kind", "primitives", "ns_per_ray_min", "embree_ns_per_ray_min", "replicate"} - set(df.columns)
    if missing:
        print(f"bvh_scale: {runs_csv}: not a runs CSV of raylab sweep (missing {', '.join(sorted(missing))})", file=sys.stderr)
        return 2
    if df.empty or not (df["ns_per_ray_min"] > 0).all() or not (df["embree_ns_per_ray_min"] > 0).all():
        print(f"bvh_scale: {runs_csv}: no rows, or a row without a positive time of ours and of Embree", file=sys.stderr)
        return 2
    thread_counts = sorted(set(df["threads"])) if "threads" in df.columns else [1]
    if len(thread_counts) != 1:
        print(f"bvh_scale: {runs_csv}: rows of {len(thread_counts)} thread counts ({', '.join(map(str, thread_counts))}); "
              "give one sweep per thread count", file=sys.stderr)
        return 2
    threads = int(thread_counts[0])
    goals = GOALS if threads == 1 else GOALS_MULTITHREAD
    df["ratio"] = df["embree_ns_per_ray_min"] / df["ns_per_ray_min"]
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    accels = list(dict.fromkeys(df["accel"]))
    scenes = df.groupby("scene")["primitives"].first().sort_values()

    rows = []
    for (scene, accel, kind), g in df.groupby(["scene", "accel", "ray_kind"]):
        m, lo, hi = median_interval(g["ratio"])
        rows.append({"scene": scene, "triangles": int(g["primitives"].iloc[0]), "accel": accel, "kind": kind,
                     "ratio": m, "lo": lo, "hi": hi, "n": len(g), "ns": float(np.median(g["ns_per_ray_min"])),
                     "embree_ns": float(np.median(g["embree_ns_per_ray_min"]))})
    table = pd.DataFrame(rows).sort_values(["accel", "kind", "triangles"])
    table.to_csv(out / "bvh_scale.csv", index=False)

    # Geometric mean over the scenes, measurement by measurement (replicate r of every scene together).
    geo = []
    for (accel, kind), g in df.groupby(["accel", "ray_kind"]):
        per_rep = g.groupby("replicate")["ratio"].apply(lambda r: float(np.exp(np.mean(np.log(r)))))
        m, lo, hi = median_interval(per_rep)
        lowest = table[(table["accel"] == accel) & (table["kind"] == kind)].sort_values("ratio").iloc[0]
        geo.append((accel, kind, m, lo, hi, len(per_rep), lowest))

    thread_words = "single thread" if threads == 1 else f"{threads} threads"
    fig, axes = plt.subplots(1, len(KINDS), figsize=(15, 5.4), sharey=True)
    colours = {a: plt.get_cmap("tab10")(i) for i, a in enumerate(accels)}
    for ax, kind in zip(axes, KINDS):
        for accel in accels:
            t = table[(table["accel"] == accel) & (table["kind"] == kind)]
            for family, marker in (("grass", "s"), ("bunny", "o")):
                f = t[t["scene"].str.contains("grass") == (family == "grass")]
                ax.errorbar(f["triangles"], f["ratio"], yerr=[f["ratio"] - f["lo"], f["hi"] - f["ratio"]], fmt=marker + "-",
                            color=colours[accel], markersize=5, capsize=3, label=f"{accel}, {family}")
        for accel, goal in goals.items():
            if accel in colours:
                ax.axhline(goal, color=colours[accel], linestyle=":", linewidth=1)
        ax.axhline(1.0, color="black", linewidth=0.6)
        ax.set_xscale("log")
        ax.set_xlabel("triangles")
        ax.set_title(f"{kind} rays", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("throughput / Embree's (fast mode), median [95%]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=len(accels), bbox_to_anchor=(0.5, 0.0))
    fig.suptitle(f"The BVH against Embree across scales, {thread_words} (dotted: the goals, "
                 f"{goals['bvh:robust=off']} for robust=off and {goals['bvh']} for the default)", fontsize=10)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(out / "bvh_scale.png", dpi=110)

    others = sorted(p for p in out.glob("threads*/README.md")) if threads == 1 else []
    md = ["# The BVH against Embree across scales" + ("" if threads == 1 else f", {threads} threads"), "",
          f"Issue 32's goals ({thread_words}): `bvh:robust=off` / `embree` ≥ {goals['bvh:robust=off']} and the default "
          f"`bvh` / `embree` (fast mode) ≥ {goals['bvh']}, on every ray kind and at every scale. Generated by",
          "", "```",
          f"build/raylab sweep --plan {plan}" + ("" if threads == 1 else f" --threads {threads}") + f" --out {runs_csv}",
          f"python3 experiments/bvh_scale.py {runs_csv} {out_dir}" + "".join(f" {b}" for b in bench_jsons)
          + ("" if plan == "data/plans/bvh_scale.json" else f" --plan {plan}"), "```", ""]
    if others:
        md += ["Other thread counts: " + ", ".join(f"[{p.parent.name.removeprefix('threads')} threads]"
                                                   f"({p.parent.name}/README.md)" for p in others) + ".", ""]
    md += ["Each case is measured 5 times: once, then 4 replicates after all other cases, each on a rebuilt "
          "structure, minutes apart. Each measurement is the minimum of at least 5 passes alternating with Embree's "
          "on the same 65,536 rays, " + ("in the tracing thread's CPU time" if threads == 1 else
                                         f"in wall-clock time on {threads} threads, ours and Embree's alike")
          + ". *ratio* is Embree's ns/ray over ours "
          "(> 1: ours is faster): the median over the 5 measurements, with its 95% percentile-bootstrap interval "
          "(2000 resamples, fixed seed).", "",
          "## Geometric means over the scenes", "",
          "Taken measurement by measurement (measurement r of every scene together), then the median over the "
          "measurements with its interval.", "",
          "| comparison | rays | geometric mean [95%] | lowest scene | goal | met? |", "|---|---|---|---|---|---|"]
    for accel, kind, m, lo, hi, n, lowest in sorted(geo, key=lambda g: (g[0], KINDS.index(g[1]) if g[1] in KINDS else 9)):
        goal = goals.get(accel)
        met = "–" if goal is None else ("yes" if lo >= goal and lowest["lo"] >= goal else "no")
        md.append(f"| `{accel}` / `embree` | {kind} | {m:.2f} [{lo:.2f}, {hi:.2f}] | {lowest['ratio']:.2f} "
                  f"({lowest['scene']}) | {'≥ ' + format(goal, '.1f') if goal else '–'} | {met} |")
    md += ["", "![throughput against Embree across scales](bvh_scale.png)", "",
           "*The figure*: one panel per ray kind; x the scene's triangles, y the ratio with its interval; circles the "
           "bunny (decimated, as scanned, refined by Loop subdivision), squares grass; dotted lines the goals.", "",
           "## Every case", "",
           "| scene | triangles | structure | rays | ns/ray | Embree ns/ray | ratio [95%] | measurements |",
           "|---|---|---|---|---|---|---|---|"]
    for _, r in table.iterrows():
        md.append(f"| {r['scene']} | {r['triangles']:.3g} | `{r['accel']}` | {r['kind']} | {r['ns']:.0f} | "
                  f"{r['embree_ns']:.0f} | {r['ratio']:.2f} [{r['lo']:.2f}, {r['hi']:.2f}] | {r['n']} |")
    md += memory_section(df)
    md += bench_md
    md += ["", f"Sweep scenes: {len(scenes)}, {scenes.min():,} to {scenes.max():,} triangles. No scene of 10^7 triangles "
           "is in the plan: the sweep computes each case's tree features, whose end-point overlap takes minutes there"
           + ("; `bench_bvh` measures them (above)." if bench_md else "."), ""]
    (out / "README.md").write_text("\n".join(md))
    print(f"bvh_scale: wrote {out / 'README.md'} and {out / 'bvh_scale.png'}")
    return 0


if __name__ == "__main__":
    args = sys.argv[1:]
    plan_arg = {}
    if "--plan" in args:
        at = args.index("--plan")
        if at + 1 >= len(args):
            print("bvh_scale: --plan needs a plan file", file=sys.stderr)
            sys.exit(2)
        plan_arg = {"plan": args[at + 1]}
        del args[at:at + 2]
    if len(args) < 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(*args, **plan_arg))
