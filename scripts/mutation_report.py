"""Score of a mutmut run (``scripts/mutation``) per judging module and overall, and its surviving
mutants.

Reads ``mutants/**/*.meta`` (mutmut 3's results) and prints, for the mutants that
``scripts/mutation`` runs (:data:`TARGETS`), one row per module: killed / tested, with timeouts,
suspicious and untested mutants counted separately, then every survivor as ``module:line  - original
/ + mutant``. Survivors listed in ``docs/mutation_survivors.md`` as equivalent are marked
``[equivalent]`` and the score is given both over all mutants and over the non-equivalent ones. Run
with the mutation venv's python from the project root.
"""
from __future__ import annotations

import ast
import fnmatch
import json
import re
import sys
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The mutants scripts/mutation runs: every function of the judging modules; in _registry.py and
#: checks.py only the answer checks and the atol / rotation checks.
TARGETS = [
    "replication.rig.quality.*", "replication.rig.diagnose.*", "replication.rig.online.*",
    "replication.rig.online_events.*", "replication.rig.live.*", "replication.study.ledger.*",
    "replication.rig.association.*", "replication.rig.offset_search.*", "replication.rig.report.*",
    "replication.rig.changepoint.*",
    "replication.core.solvers._registry.x_check_answer__mutmut_*",
    "replication.core.solvers._registry.x__checked_answer__mutmut_*",
    "replication.core.solvers._registry.x__screen_gross__mutmut_*",
    "replication.core.solvers._registry.x__warn_not_rotations__mutmut_*",
    "replication.core.solvers._registry.x_check_local_answer__mutmut_*",
    "replication.core.checks.x_check_atol__mutmut_*", "replication.core.checks.x_check_number__mutmut_*",
    "replication.core.checks.x_check_rotation_matrices__mutmut_*",
    "replication.core.checks.x_check_rotation_flat__mutmut_*",
]

#: Written by ``scripts/mutation --unit`` under mutants/: the mutants (names or patterns) last run
#: against their unit's test files only; one not killed there has not yet met every test
#: (``--survivors`` runs it against them all and removes this file).
UNIT_ONLY = "unit-only.txt"
#: Written by a run against every test after ``--unit`` (a GLOB's mutants): those no longer count
#: as met by their unit's tests only.
FULL_AFTER_UNIT = "full-after-unit.txt"

STATUS = {1: "killed", 3: "killed", 0: "survived", 5: "no tests", 33: "no tests", None: "not checked",
          36: "timeout", -24: "timeout", 24: "timeout", 152: "timeout", 255: "timeout", -11: "segfault", -9: "segfault"}


def targeted(key: str) -> bool:
    return any(fnmatch.fnmatch(key, t) for t in TARGETS)


def equivalent_ids() -> set[str]:
    """Mutant ids declared equivalent in docs/mutation_survivors.md (the first column of its
    tables)."""
    doc = ROOT / "docs" / "mutation_survivors.md"
    if not doc.exists():
        return set()
    return set(re.findall(r"^\|\s*`?(replication\.[^|`\s]+__mutmut_\d+)`?\s*\|", doc.read_text(), flags=re.M))


def function_span(source: str, mangled: str) -> tuple[int, int]:
    """First and last line of the function ``x_name`` or method ``xǁClassǁname`` in ``source``."""
    if "ǁ" in mangled:
        _, cls, name = mangled.split("ǁ")
    else:
        cls, name = None, mangled[2:]
    tree = ast.parse(source)
    body = tree.body
    if cls:
        body = next(n.body for n in ast.walk(tree) if isinstance(n, ast.ClassDef) and n.name == cls)
    node = next(n for n in body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name == name)
    start = min([node.lineno] + [d.lineno for d in node.decorator_list])
    return start, node.end_lineno


def describe(key: str, path: Path, source: str) -> tuple[int, str, str]:
    """(line in the source, original line, mutated line) of a mutant."""
    from mutmut.mutation.diff_apply import get_diff_for_mutant

    diff = get_diff_for_mutant(key, path=str(path)).splitlines()
    minus = [line[1:] for line in diff if line.startswith("-") and not line.startswith("---")]
    plus = [line[1:] for line in diff if line.startswith("+") and not line.startswith("+++")]
    hunk, offset = 1, 0  # line of the first removed line within the function's code
    for i, line in enumerate(diff):
        if m := re.match(r"@@ -(\d+)", line):
            hunk = int(m.group(1))
            offset = next((j for j, l in enumerate(diff[i + 1:]) if l.startswith("-")), 0)
            break
    mangled = key.partition("__mutmut_")[0].rpartition(".")[2]
    start, end = function_span(source, mangled)
    lines = source.splitlines()
    guess = start + hunk - 1 + offset
    if minus:
        want = minus[0].strip()
        hits = [n for n in range(start, end + 1) if lines[n - 1].strip() == want]
        if hits:
            guess = min(hits, key=lambda n: abs(n - guess))
    return guess, " ".join(m.strip() for m in minus), " ".join(p.strip() for p in plus)


def rerun_names() -> list[str]:
    """The target mutants of the last run that were not killed (survivors, untested, timeouts,
    suspicious, not run), but those declared equivalent (a re-run cannot kill them, and each
    costs every test that calls its function)."""
    equivalent = equivalent_ids()
    names = []
    for meta in sorted((ROOT / "mutants").rglob("*.py.meta")):
        for key, code in json.loads(meta.read_text())["exit_code_by_key"].items():
            if targeted(key) and STATUS.get(code, "suspicious") != "killed" and key not in equivalent:
                names.append(key)
    return names


def _patterns(name: str) -> list[str]:
    path = ROOT / "mutants" / name
    return path.read_text().split() if path.exists() else []


def unit_only(key: str, unit: list[str], full: list[str]) -> bool:
    """Whether mutant ``key`` was last run against its unit's tests only: it matches one of
    :data:`UNIT_ONLY`'s ``unit`` patterns and none of :data:`FULL_AFTER_UNIT`'s ``full``."""
    return any(fnmatch.fnmatch(key, p) for p in unit) and not any(fnmatch.fnmatch(key, p) for p in full)


def pending_names() -> list[str]:
    """What a resumed run tests: each target (a pattern) of a module without results or whose source
    changed since its last result, and in every other module the target mutants without a result
    (a stopped run's rest). Empty when every target mutant has a result."""
    names = []
    for target in TARGETS:
        module = re.split(r"\.(?:x_|\*)", target)[0]
        source = ROOT / (module.replace(".", "/") + ".py")
        meta = ROOT / "mutants" / (module.replace(".", "/") + ".py.meta")
        if not meta.exists() or source.stat().st_mtime > meta.stat().st_mtime:
            names.append(target)
            continue
        codes = json.loads(meta.read_text())["exit_code_by_key"]
        names += [key for key, code in codes.items() if code is None and fnmatch.fnmatch(key, target)]
    return list(dict.fromkeys(names))


def main() -> int:
    sys.path.insert(0, str(ROOT))
    if sys.argv[1:] == ["--rerun-names"]:
        print("\n".join(rerun_names()))
        return 0
    if sys.argv[1:] == ["--pending-names"]:
        print("\n".join(pending_names()))
        return 0
    equivalent = equivalent_ids()
    unit, full = _patterns(UNIT_ONLY), _patterns(FULL_AFTER_UNIT)
    counts: dict[str, Counter] = defaultdict(Counter)
    survivors = []
    for meta in sorted((ROOT / "mutants").rglob("*.py.meta")):
        path = meta.relative_to(ROOT / "mutants").with_suffix("")
        source = (ROOT / path).read_text()
        module = str(path.with_suffix("")).replace("/", ".")
        exit_codes = json.loads(meta.read_text())["exit_code_by_key"]
        for key, code in exit_codes.items():
            if not targeted(key):
                continue
            status = STATUS.get(code, "suspicious")
            if status == "survived" and key in equivalent:
                status = "equivalent"
            elif status in ("survived", "no tests") and unit_only(key, unit, full):
                status = "unit only"
            counts[module][status] += 1
            if status in ("survived", "equivalent", "unit only"):
                survivors.append((module, key, path, source, status))
    if not counts:
        print("no mutmut results under mutants/: run scripts/mutation first")
        return 1

    cols = ["killed", "survived", "equivalent", "unit only", "timeout", "suspicious", "segfault", "no tests",
            "not checked"]
    print(f"{'module':36} {'total':>6} " + " ".join(f"{c:>11}" for c in cols) + f" {'score':>7} {'non-eq':>7}")
    total = Counter()
    for module in sorted(counts):
        total.update(counts[module])
    for module, c in sorted(counts.items()) + [("OVERALL", total)]:
        n = sum(c.values())
        # killed over everything run (timeouts, suspicious, no tests count against it); non-eq:
        # equivalents left out
        score = c["killed"] / n if n else float("nan")
        nonequiv = c["killed"] / (n - c["equivalent"]) if n > c["equivalent"] else float("nan")
        print(f"{module:36} {n:>6} " + " ".join(f"{c[k]:>11}" for k in cols) + f" {score:>7.1%} {nonequiv:>7.1%}")

    if total["unit only"]:
        print(f"\n{total['unit only']} mutants were run against their unit's test files only (--unit) and "
              f"not killed there; until `bash scripts/mutation --survivors` runs them against every test, each "
              f"score is a lower bound")
    print(f"\nsurvivors ({sum(1 for s in survivors if s[4] == 'survived')} surviving, "
          f"{sum(1 for s in survivors if s[4] == 'unit only')} not killed by their unit's tests alone, "
          f"{sum(1 for s in survivors if s[4] == 'equivalent')} declared equivalent in docs/mutation_survivors.md):")
    for _module, key, path, source, status in sorted(survivors, key=lambda s: (s[0], s[1])):
        try:
            line, old, new = describe(key, path, source)
        except Exception as exc:  # a report line, never a crash of the report
            line, old, new = 0, f"(diff unavailable: {exc})", ""
        mark = {"equivalent": " [equivalent]", "unit only": " [unit tests only]"}.get(status, "")
        print(f"{path}:{line}  {key.rpartition('.')[2]}{mark}\n    - {old}\n    + {new}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
