#!/usr/bin/env bash
# `make demo`: the lecture's examples, solved offline and run through the generator node.
# Plots go to out/. The node runs in its own ROS domain, localhost only, and is stopped at
# the end (also on failure). Every step waits for an answer: no sleeps.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
BIN=$(dirname "$PY")  # the console scripts `make` installs beside it: traj-gen, generator
OUT=${OUT:-out}
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
export ROS_DOMAIN_ID=${DEMO_DOMAIN_ID:-$((1 + $$ % 100))}
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
unset ROS_LOCALHOST_ONLY
mkdir -p "$OUT"
traj_gen() { echo "\$ traj-gen $*"; "$BIN/traj-gen" "$@"; }

echo '== Offline (core solver only): the 15° → 75° cubic in 3 s, and LSPB through via points'
traj_gen solve cubic --points 15 75 --duration 3 --degrees
traj_gen plot cubic --points 15 75 --duration 3 --degrees -o "$OUT/cubic_15_75.png"
traj_gen solve lspb --points 10 35 25 10 --durations 2 1 3 --acceleration 50 --degrees
traj_gen plot lspb --points 10 35 25 10 --durations 2 1 3 --acceleration 50 --degrees \
  -o "$OUT/lspb_via.png"

node_pid=
start_node() {
  echo "== generator node ($*), ROS_DOMAIN_ID=$ROS_DOMAIN_ID, log in $OUT/node.log"
  "$BIN/generator" --ros-args --params-file config/generator.yaml \
    "$@" >>"$OUT/node.log" 2>&1 &
  node_pid=$!
}
stop_node() {
  if [ -n "$node_pid" ]; then kill -INT "$node_pid"; wait "$node_pid" || true; node_pid=; fi
}
trap stop_node EXIT
record() { traj_gen plot --topic /trajectory_generator/trajectory --degrees -o "$OUT/$1"; }

start_node -p profile:=cubic
traj_gen goal joint_1=15 --degrees --wait
traj_gen via --joints joint_1 --degrees --point 15 @0 --point 75 @3 --wait
record node_cubic_15_75.png
stop_node

start_node -p profile:=lspb -p lspb_acceleration:=0.8726646259971648  # 50 deg/s²
traj_gen goal joint_1=10 --degrees --wait
traj_gen via --joints joint_1 --degrees --point 10 @0 --point 35 @2 --point 25 @3 \
  --point 10 @6 --wait
record node_lspb_via.png
traj_gen goal joint_1=0.5 joint_2=-1.0 --wait
record node_lspb_goal.png
stop_node
echo "== plots:"; ls -1 "$OUT"/*.png
