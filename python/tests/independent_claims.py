"""The claims of ``toolconf reproduce --model`` recomputed independently: from ``toolconf select
--json`` on the same tools (the same model, seed and count), with SciPy's Spearman ρ and
Wilcoxon signed-rank test and a NumPy percentile bootstrap, not toolconf's statistics.

Shared by python/tests/test_reproduce.py (the UR5 on a task written by the test) and
python/loaded_tests (the xArm7, a robot the repository does not ship as a model).
"""

import csv
import json
from pathlib import Path

import numpy as np
from scipy import stats

# How close the command's numbers must be to the independent ones.
TOLERANCE = 0.02
# Bootstrap resamples of the independent interval (more than the command's 2000, so that its
# own Monte-Carlo error is small against the tolerance).
RESAMPLES = 4000


def spearman(x, y) -> float:
    return float(stats.spearmanr(x, y).statistic)


def bootstrap(x, y, seed: int) -> tuple[float, float]:
    """The 95 % percentile interval of Spearman's ρ over resamples of the pairs."""
    rng = np.random.default_rng(seed)
    x, y = np.asarray(x), np.asarray(y)
    values = []
    for _ in range(RESAMPLES):
        i = rng.integers(0, len(x), len(x))
        values.append(spearman(x[i], y[i]))
    return float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))


def verdict(low: float, high: float) -> str:
    """The rule the command states, applied to the independent interval."""
    return "holds" if high < 0 else "reversed" if low > 0 else "no relation"


def decisive(low: float, high: float) -> bool:
    """Whether the verdict cannot flip within the tolerance (neither end near 0)."""
    return min(abs(low), abs(high)) > TOLERANCE


def select(cli_json, prefix, model, task, n, seed):
    """``select --json``'s tools, by index."""
    out = cli_json(*prefix, "select", "--models", model, "--task-file", task, "--tools", n, "--seed", seed)
    return out["tools"]


def check(cli, cli_json, prefix, model, task_text, perturbation, folder: Path, n=200, seed=7):
    """Runs ``reproduce --model`` and ``select`` (without and with ΔT) on the same tools and
    compares every claim's statistic and verdict; returns the command's verdicts."""
    perturbed = folder / "task.toml"
    perturbed.write_text(task_text + f"[episode]\nperturbation = {perturbation}\n")
    still = folder / "task_without_perturbation.toml"
    still.write_text(task_text)
    out = folder / "out"
    status, stdout, stderr = cli(*prefix, "reproduce", "--model", model, "--task-file", perturbed,
                                 "--sample", n, "--seed", seed, "--sweep-tools", 20, "--json",
                                 "--out", out)
    assert status == 0, stderr
    ours = json.loads(stdout)["verdicts"]
    base = select(cli_json, prefix, model, still, n, seed)
    under = select(cli_json, prefix, model, perturbed, n, seed)
    logdet = np.array([t["logdet"] for t in base])
    error = np.array([t["task_error"] for t in base])
    change = np.abs(np.array([t["task_error"] for t in under]) - error)
    for key, y in (("confidence_predicts_task_error", error), ("confidence_predicts_reliability", change)):
        rho = spearman(logdet, y)
        low, high = bootstrap(logdet, y, seed)
        stat = ours[key]["statistic"]
        assert abs(stat["rho"] - rho) <= TOLERANCE, (key, stat, rho)
        assert abs(stat["ci"][0] - low) <= TOLERANCE and abs(stat["ci"][1] - high) <= TOLERANCE, (key, stat, low, high)
        assert decisive(low, high), f"{key}: the interval [{low}, {high}] ends near 0; choose another seed"
        assert ours[key]["verdict"] == verdict(low, high), (key, ours[key], low, high)
    check_selection(ours["free_energy_choices_less_sensitive"], base, change, out / "fig7_benchmark.csv")
    return {key: v["verdict"] for key, v in ours.items()}


def check_selection(ours, base, change, benchmark: Path):
    """Claim (c): each trial's tools (the command's fig7 CSV), chosen again by ∫F and ∫J from
    ``select``'s numbers, and SciPy's Wilcoxon signed-rank test on J's − F's sensitivity."""
    trials = {}
    with benchmark.open() as f:
        for row in csv.DictReader(f):
            trials.setdefault(int(row["trial"]), []).append(int(row["tool"]))
    d = []
    for tools in trials.values():
        f = min(tools, key=lambda i: (base[i]["free_energy"], tools.index(i)))
        j = min(tools, key=lambda i: (base[i]["cost_j"], tools.index(i)))
        d.append(change[j] - change[f])
    d = np.array(d)
    nonzero = d[d != 0]
    if len(nonzero) == 0:
        assert ours["verdict"] == "no relation", ours
        return
    p = float(stats.wilcoxon(nonzero, zero_method="wilcox", correction=False, method="approx").pvalue)
    stat = ours["statistic"]
    assert abs(stat["mean_difference"] - d.mean()) <= TOLERANCE * max(1.0, abs(d.mean())), (stat, d.mean())
    assert abs(stat["wilcoxon_p"] - p) <= TOLERANCE, (stat, p)
    expected = "no relation" if p >= 0.05 else ("holds" if d.mean() > 0 else "reversed")
    assert abs(p - 0.05) > TOLERANCE, f"p = {p} is too near 0.05 to compare verdicts; choose another seed"
    assert ours["verdict"] == expected, (ours, p, d.mean())
