# `rvlio refine` of one long recording as N chunk jobs, then `rvlio merge`
# (docs/refine.md). One job per chunk (`rvlio refine --chunk K --of N`,
# each keeping only its part of the recording in memory), then one merge job. Runs
# locally or on Slurm through the same profile as the ablation grid:
#
#   snakemake -s workflow/refine_chunks.smk -j 2 \
#             --config bag=rec.bag init=run/trajectory.tum chunks=4 out=out/refined \
#                      config=[sensors.yaml] set=[refine.job_overlap_s=10]
#   snakemake -s workflow/refine_chunks.smk --profile workflow/profiles/slurm --config ...
#
# config: bag, init (required), chunks (N, default 4), out (default
# "refined"), config (list of --config files), set (list of KEY=VALUE
# overrides), rvlio (default build/bin/rvlio of this repository), and per
# chunk job cpus (default 1), mem_mb (default 4000), runtime (minutes,
# default 120). Paths are relative to Snakemake's working directory.
#
# Outputs: OUT/chunk_K/ (trajectory.tum, map.pcd, summary.json, chunk.json),
# OUT/merged/ (trajectory.tum, map.pcd, summary.json), logs in OUT/logs/.

import os

from snakemake.exceptions import WorkflowError

REPO = os.path.abspath(os.path.join(workflow.basedir, ".."))
RVLIO = os.path.abspath(config.get("rvlio", os.path.join(REPO, "build", "bin", "rvlio")))
for key in ("bag", "init"):
    if key not in config:
        raise WorkflowError("give the recording and its initial trajectory: --config bag=BAG "
                            "init=TUM [chunks=N] [out=DIR] [config=[FILE,...]] [set=[KEY=VALUE,...]]")
if not os.access(RVLIO, os.X_OK):
    raise WorkflowError("rvlio not found at %s (build it, or --config rvlio=PATH)" % RVLIO)


def as_list(value):
    """A --config value given once (a string) or as a list."""
    if value is None:
        return []
    return [str(v) for v in value] if isinstance(value, (list, tuple)) else [str(value)]


try:
    N = int(config.get("chunks", 4))
except ValueError:
    raise WorkflowError("chunks=%s: not a whole number" % config.get("chunks"))
if N < 1:
    raise WorkflowError("chunks=%d: needs at least 1 chunk" % N)
OUT = str(config.get("out", "refined"))
REFINE = [RVLIO, "refine", "--bag", str(config["bag"]), "--init", str(config["init"])]
for f in as_list(config.get("config")):
    REFINE += ["--config", f]
for kv in as_list(config.get("set")):
    REFINE += ["--set", kv]
CPUS = int(config.get("cpus", 1))
MEM_MB = int(config.get("mem_mb", 4000))
RUNTIME = int(config.get("runtime", 120))
CHUNKS = list(range(1, N + 1))

wildcard_constraints:
    k="[0-9]+",

localrules: all


rule all:
    input:
        os.path.join(OUT, "merged", "trajectory.tum"),


rule chunk:
    """Chunk K of N: `rvlio refine --chunk K --of N` into OUT/chunk_K."""
    input:
        bag=str(config["bag"]),
        init=str(config["init"]),
    output:
        os.path.join(OUT, "chunk_{k}", "chunk.json"),
    log:
        os.path.join(OUT, "logs", "chunk_{k}.log"),
    params:
        refine=REFINE,
        n=N,
        dir=lambda wildcards: os.path.join(OUT, "chunk_" + wildcards.k),
    threads: CPUS
    resources:
        cpus_per_task=CPUS,
        mem_mb=MEM_MB,
        runtime=RUNTIME,
    shell:
        "{params.refine:q} --set refine.threads={threads} --chunk {wildcards.k} "
        "--of {params.n} --out {params.dir:q} > {log:q} 2>&1"


rule merge:
    """`rvlio merge` of the N chunk folders into OUT/merged."""
    input:
        expand(os.path.join(OUT, "chunk_{k}", "chunk.json"), k=CHUNKS),
    output:
        os.path.join(OUT, "merged", "trajectory.tum"),
        os.path.join(OUT, "merged", "map.pcd"),
        os.path.join(OUT, "merged", "summary.json"),
    log:
        os.path.join(OUT, "logs", "merge.log"),
    params:
        rvlio=RVLIO,
        chunks=[a for k in CHUNKS for a in ("--chunks", os.path.join(OUT, "chunk_%d" % k))],
        out=os.path.join(OUT, "merged"),
    threads: 1
    resources:
        cpus_per_task=1,
        mem_mb=MEM_MB,
        runtime=RUNTIME,
    shell:
        "{params.rvlio:q} merge {params.chunks:q} --out {params.out:q} > {log:q} 2>&1"
