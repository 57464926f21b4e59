"""Sweep of bad inputs (issue 13): run every case of tests/test_bad_input.py and classify the outcome.

    python notes/issue13_sweep.py            # the installed tissuemech
    PYTHONPATH=/path/to/pkgroot python notes/issue13_sweep.py   # another checkout (a folder holding tissuemech/)

Classes: clear (ValueError/TypeError naming the quantity), other-clear (another exception naming it),
unclear (an exception whose message does not name it), silent-nonfinite / silent-number (no error).
"""

import os
import re
import sys
import warnings
from collections import Counter

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import numpy as np
import test_bad_input as t

SKIP = os.environ.get("SWEEP_SKIP")  # a regex of case names not to run (e.g. "huge" on code that exhausts memory)
counts, rows = Counter(), []
for name, call, _exc, words in t.CASES:
    if SKIP and re.search(SKIP, name):
        counts["skipped"] += 1
        rows.append(("skipped", name))
        continue
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            out = call()
        except (ValueError, TypeError) as e:
            kind = "clear" if re.search(words, str(e)) else "unclear"
        except Exception as e:
            kind = "other-clear" if re.search(words, str(e)) else "unclear"
        else:
            try:
                vals = np.concatenate(
                    [np.ravel(np.asarray(v, dtype=float)) for v in (out if isinstance(out, tuple) else [out])]
                )
                kind = "silent-nonfinite" if not np.all(np.isfinite(vals)) else "silent-number"
            except Exception:
                kind = "silent-number"
    counts[kind] += 1
    rows.append((kind, name))
for kind, name in rows:
    if kind != "clear":
        print(f"{kind:18s} {name}", flush=True)
print(dict(counts), "of", len(t.CASES))
