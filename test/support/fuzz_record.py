"""Where the reliability fuzz writes its figures: out/reliability_fuzz.json, one part a layer."""

import json

from node_harness import REPO

RESULTS = REPO / 'out' / 'reliability_fuzz.json'


def record(layer: str, figures: dict) -> None:
    RESULTS.parent.mkdir(exist_ok=True)
    data = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    data[layer] = figures
    RESULTS.write_text(json.dumps(data, indent=2, sort_keys=True))
