#!/usr/bin/env bash
# Seeds the fuzz corpora from committed files, then runs every target for a minute:
#   bash fuzz/seed-corpus.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p corpus/instance corpus/assignment corpus/configs corpus/mission
head -n 1 ../datasets/n20.jsonl > corpus/instance/n20_first_line
cp ../models/paper/afgnet_ddqn_n20/config.json corpus/configs/run_config.json
python3 -c 'import json, sys; json.dump(json.load(open(sys.argv[1]))["network"], open(sys.argv[2], "w"))' \
    ../models/paper/afgnet_ddqn_n20/model.json corpus/configs/network.json
python3 -c 'import json; print(json.dumps({"format": "afg-assignment", "version": 1, "tasks": [i % 5 for i in range(20)]}))' \
    > corpus/assignment/round_robin.json
cargo run --quiet --release --manifest-path ../Cargo.toml -p afg-cli -- mission gen --preset attrition \
    --robots 12 --tasks 4 --seed 1 --out corpus/mission/attrition.json > /dev/null
for target in instance assignment configs mission; do
    cargo +nightly fuzz run "$target" -- -max_total_time="${1:-60}" -rss_limit_mb=2048 2>&1 | grep -E '^Done|SUMMARY|panicked'
done
