#!/usr/bin/env python3
"""The scheduler files in tools/distributed run the sharded bake's protocol (docs/distributed.md).

Kubernetes: bake-shards.yaml and bake-merge.yaml are parsed as YAML and checked for what the protocol needs
(an Indexed Job whose completions equal the N of its --shard; an Indexed merge Job of W + 1 pods, pod 0 the
merge over the parts with a trace farm of --workers W, the others its workers); then the commands they hold
are run as the pods would run them (sh -c with JOB_COMPLETION_INDEX set, the volume's paths mapped to a work
directory; the merge Job's pods all at once). Slurm: bake.slurm passes `bash -n` and runs, as array tasks
would, in three protocols (shard + merge; round1, floor, round2, merge; shard + farm, the farm's tasks at
once). Each protocol's level must equal the one-process bake with the same options, byte for byte.

usage: scheduler_manifests_test.py TETRAPROBE SOURCE_DIR WORK_DIR
"""
import filecmp
import os
import re
import shutil
import subprocess
import sys

import yaml

# Small budgets: the protocol is what is checked, not the light (as run_local.sh's ctest entries).
OPTIONS = ["--samples", "64", "--max-samples", "512", "--path-budget", "1000000", "--refine-points", "512",
           "--threads", "1"]


def fail(message):
    print("scheduler manifests: " + message, file=sys.stderr)
    sys.exit(1)


def run(cmd, env=None, shell=False):
    r = subprocess.run(cmd, env=env, shell=shell, capture_output=True, text=True)
    if r.returncode != 0:
        fail("command failed (%d): %s\n%s%s" % (r.returncode, cmd, r.stdout[-2000:], r.stderr[-2000:]))
    return r


def run_at_once(cmds):
    """Runs (cmd, env) pairs as concurrent processes, as a scheduler starts an array; fails if any fails."""
    procs = [subprocess.Popen(c, env=e, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for c, e in cmds]
    outs = [p.communicate(timeout=600) for p in procs]
    for (c, _), p, (out, err) in zip(cmds, procs, outs):
        if p.returncode != 0:
            fail("command failed (%d): %s\n%s%s" % (p.returncode, c, out[-2000:], err[-2000:]))


def job_command(doc, what):
    if doc.get("apiVersion") != "batch/v1" or doc.get("kind") != "Job":
        fail(what + ": not a batch/v1 Job")
    containers = doc["spec"]["template"]["spec"]["containers"]
    if len(containers) != 1:
        fail(what + ": expected one container")
    c = containers[0]
    if c.get("command") != ["/bin/sh", "-c"] or len(c.get("args", [])) != 1:
        fail(what + ": expected command [/bin/sh, -c] and one argument")
    if doc["spec"]["template"]["spec"].get("restartPolicy") != "Never":
        fail(what + ": restartPolicy must be Never (a retried shard rewrites its part atomically)")
    return c["args"][0]


def main():
    if len(sys.argv) != 4:
        fail("usage: scheduler_manifests_test.py TETRAPROBE SOURCE_DIR WORK_DIR")
    tp, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
    dist = os.path.join(src, "tools", "distributed")
    scene = os.path.join(src, "samples", "two_rooms", "two_rooms.scene.json")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)

    single = os.path.join(work, "single.tpb")
    run([tp, "bake", scene, "-o", single] + OPTIONS)

    # Kubernetes.
    with open(os.path.join(dist, "bake-shards.yaml")) as f:
        shards = yaml.safe_load(f)
    with open(os.path.join(dist, "bake-merge.yaml")) as f:
        merge = yaml.safe_load(f)
    spec = shards["spec"]
    if spec.get("completionMode") != "Indexed":
        fail("bake-shards.yaml: completionMode must be Indexed (pods learn their shard from the index)")
    n = int(spec["completions"])
    shard_cmd = job_command(shards, "bake-shards.yaml")
    merge_cmd = job_command(merge, "bake-merge.yaml")
    m = re.search(r"--shard \$\{JOB_COMPLETION_INDEX\}/(\d+)", shard_cmd)
    if not m or int(m.group(1)) != n:
        fail("bake-shards.yaml: --shard ${JOB_COMPLETION_INDEX}/N with N = completions (%d) expected" % n)
    if "tetraprobe merge" not in merge_cmd or "shard*.part" not in merge_cmd:
        fail("bake-merge.yaml: expected `tetraprobe merge .../shard*.part`")
    mspec = merge["spec"]
    pods = int(mspec["completions"])
    w = re.search(r"--workers (\d+)", merge_cmd)
    if mspec.get("completionMode") != "Indexed" or int(mspec.get("parallelism", 1)) != pods:
        fail("bake-merge.yaml: an Indexed Job whose pods all run at once (parallelism == completions)")
    if not w or int(w.group(1)) != pods - 1 or "tetraprobe worker" not in merge_cmd:
        fail("bake-merge.yaml: the merge with --workers W = completions - 1 (%d) and the workers expected" %
             (pods - 1))
    if "--index $((JOB_COMPLETION_INDEX - 1))/%d" % (pods - 1) not in merge_cmd:
        fail("bake-merge.yaml: workers take --index $((JOB_COMPLETION_INDEX - 1))/W")
    k8s = os.path.join(work, "k8s")
    os.makedirs(os.path.join(k8s, "out"))

    def local(cmd):
        cmd = cmd.replace("/data/level/scene.scene.json", scene).replace("/data/out", os.path.join(k8s, "out"))
        return re.sub(r"\btetraprobe (bake|merge|worker) ", tp + r" \1 ", cmd.strip())

    for i in range(n):
        env = dict(os.environ, JOB_COMPLETION_INDEX=str(i))
        run(["/bin/sh", "-c", local(shard_cmd) + " " + " ".join(OPTIONS)], env=env)
    run_at_once([(["/bin/sh", "-c", local(merge_cmd)], dict(os.environ, JOB_COMPLETION_INDEX=str(i)))
                 for i in range(pods)])
    level = os.path.join(k8s, "out", "level.tpb")
    if not filecmp.cmp(level, single, shallow=False):
        fail("the Kubernetes Jobs' level differs from the one-process bake")
    print("Kubernetes: %d indexed shards and the merge Job (%d workers): identical to the one-process bake" %
          (n, pods - 1))

    # Slurm, both protocols.
    slurm = os.path.join(dist, "bake.slurm")
    run(["bash", "-n", slurm])
    for protocol, steps in (("one round", [("shard", True), ("merge", False)]),
                            ("two rounds", [("round1", True), ("floor", False), ("round2", True),
                                            ("merge", False)]),
                            ("farm", [("shard", True), ("farm", "at once")])):
        out = os.path.join(work, "slurm_" + protocol.replace(" ", "_"))
        n = 3
        for mode, array in steps:
            cmds = []
            for i in range(n if array else 1):
                # The script passes --threads from SLURM_CPUS_PER_TASK itself.
                env = dict(os.environ, TETRAPROBE=tp, BAKE_OPTIONS=" ".join(OPTIONS[:-2]), SLURM_CPUS_PER_TASK="1")
                if array:
                    env.update(SLURM_ARRAY_TASK_COUNT=str(n), SLURM_ARRAY_TASK_ID=str(i))
                cmds.append((["bash", slurm, mode, scene, out], env))
            if array == "at once":
                run_at_once(cmds)
            else:
                for c, env in cmds:
                    run(c, env=env)
        if not filecmp.cmp(os.path.join(out, "level.tpb"), single, shallow=False):
            fail("Slurm (%s): the level differs from the one-process bake" % protocol)
        print("Slurm (%s): %d array tasks a round: identical to the one-process bake" % (protocol, n))
    print("scheduler manifests: ok")


if __name__ == "__main__":
    main()
