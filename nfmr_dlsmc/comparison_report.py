"""``report.md`` of ``nfmr-compare``: the paper's Tables 2-4 beside ours, the convergence
times of section 4.2, the paper's qualitative findings checked, and the figures."""

from dataclasses import dataclass
from pathlib import Path

from nfmr_dlsmc.comparison_metrics import (BAND_WINDOW, HEADING_TOLERANCE, PAPER_TABLE2,
                                           PAPER_TABLE3, PAPER_TABLE4, PULSE_RECOVERY)
from nfmr_dlsmc.comparison_scenarios import CASE1_LATERAL, CASE1_LONGITUDINAL, CASE2
from nfmr_dlsmc.controllers import CONTROLLER_LABELS, CONTROLLER_NAMES
from nfmr_dlsmc.gains import InnerLoopGains, InputLimits

#: Column order of Table 2 (the paper's) and the controllers it does not have.
TABLE2_COLUMNS = ("pid", "csmc", "dl_crsmc", "dntsmc", "btsmc_ntsmc", "dlsmc")
INNER_COLUMNS = ("btintsmc_crsmc", "btintsmc_ntsmc", "dlsmc")
#: omega_raw total variation [rad/s^2] above which a law counts as chattering: a smooth
#: yaw rate on the sine needs about 0.1 rad/s^2.
CHATTER_TV = 10.0


@dataclass(frozen=True)
class Finding:
    """One qualitative claim of the paper and whether our runs reproduce it."""

    claim: str
    reproduced: bool | None
    evidence: str


def _num(value, digits: int = 4) -> str:
    if value is None:
        return "—"
    return f"{value:.{digits}f}"


def _time(value) -> str:
    return "never" if value is None else f"{value:.2f}"


def _pct(ours, paper) -> str:
    if ours is None or paper in (None, 0):
        return ""
    return f" ({100.0 * (ours - paper) / paper:+.1f}%)"


def _label(name: str) -> str:
    return CONTROLLER_LABELS.get(name, name)


def criteria_table(runs: dict, columns, paper: dict, prefix: str = "") -> list[str]:
    """Rows IAE / ISE / STD (ours, then the paper's where published), one column per method."""
    present = [c for c in columns if c in runs]
    lines = ["| criterion | " + " | ".join(_label(c) for c in present) + " |",
             "|---|" + "---:|" * len(present)]
    for key, label in (("iae", "IAE"), ("ise", "ISE"), ("std", "STD")):
        values = [runs[c].get(prefix + key) for c in present]
        lines.append(f"| {label} (nfmr) | " + " | ".join(_num(v) for v in values) + " |")
        if any(c in paper for c in present):
            cells = []
            for c, v in zip(present, values):
                published = paper.get(c, {}).get(key)
                cells.append("—" if published is None else f"{published:.4f}{_pct(v, published)}")
            lines.append(f"| {label} (paper) | " + " | ".join(cells) + " |")
    return lines


def convergence_table(runs: dict, columns) -> list[str]:
    """Convergence times of section 4.2 with the paper's where published."""
    present = [c for c in columns if c in runs]
    lines = ["| convergence time [s] | " + " | ".join(_label(c) for c in present) + " |",
             "|---|" + "---:|" * len(present)]
    rows = (("t_conv", "position (distance <= 1 mm)"),
            ("theta_r_t_conv", f"theta_r (abs(theta - theta_r) <= {HEADING_TOLERANCE} rad)"),
            ("s_y_t_conv", "s_y (abs(s_y) <= 1 mm)"))
    for key, label in rows:
        cells = []
        for c in present:
            cell = _time(runs[c].get(key))
            published = PAPER_TABLE2.get(c, {}).get(key)
            if published is not None:
                cell += f" (paper {published:g})"
            cells.append(cell)
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def summary_table(runs: dict) -> list[str]:
    """Every controller of one run: criteria, convergence and input figures."""
    lines = ["| controller | IAE [m·s] | ISE [m²·s] | STD [m] | t_conv [s] | final distance [m] "
             "| max abs omega_raw [rad/s] | steps with omega_raw over limit | "
             "omega_raw TV, 2nd half [rad/s²] |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name in CONTROLLER_NAMES:
        if name not in runs:
            continue
        r = runs[name]
        lines.append(
            f"| {_label(name)} | {_num(r['iae'])} | {_num(r['ise'])} | {_num(r['std'])} | "
            f"{_time(r['t_conv'])} | {_num(r['final_distance'])} | "
            f"{_num(r['max_abs_omega_raw'], 3)} | {100.0 * r['omega_raw_over_limit']:.2f}% | "
            f"{_num(r['omega_raw_tv'], 2)} |")
    return lines


def _band_explanation(bands: dict, eps: float) -> str:
    holding = [n for n in INNER_COLUMNS[:2] if bands[n] is not None and bands[n] <= eps]
    if not holding:
        return ""
    return (f" {' and '.join(_label(n) for n in holding)} holds the band too: with its "
            "tuned rate above the 0.5 rad/s pulse and a 1 kHz loop on the kinematic model, "
            "nothing in the plant lets theta_e drift further (the paper reports about "
            "+-0.18 rad for the other loops).")


def paper_findings(document: dict) -> list[Finding]:
    """The paper's qualitative findings (section 4.2) checked against our runs."""
    findings = []
    case1 = document.get("case1", {}).get(CASE1_LONGITUDINAL.start_key, {})
    case2 = document.get("case2", {}).get(CASE2.start_key, {})
    paper_methods = [n for n in TABLE2_COLUMNS if n in case1 and case1[n]["iae"] is not None]
    if "dlsmc" in paper_methods and len(paper_methods) > 1:
        best_iae = min(paper_methods, key=lambda n: case1[n]["iae"])
        best_std = min(paper_methods, key=lambda n: case1[n]["std"])
        ranking = ", ".join(f"{_label(n)} {case1[n]['iae']:.3f} / {case1[n]['std']:.4f}"
                            for n in sorted(paper_methods, key=lambda n: case1[n]["iae"]))
        lowest = best_iae == "dlsmc" and best_std == "dlsmc"
        findings.append(Finding(
            "DLSMC has the lowest IAE and STD among the paper's methods on Case 1 (1, 4, 0).",
            lowest, f"IAE / STD, lowest IAE first: {ranking}." + ("" if lowest else
                " The DLSMC runs the paper's untuned gains against baselines tuned on this "
                "very criterion (see Tuning below).")))
    if "dsmc" in case1:
        r = case1["dsmc"]
        findings.append(Finding(
            "DSMC fails to reach the trajectory from (1, 4, 0).", r["t_conv"] is None,
            f"DSMC: t_conv {_time(r['t_conv'])}, distance after 100 s "
            f"{_num(r['final_distance'], 3)} m."))
    if "csmc" in case1:
        r = case1["csmc"]
        omega_max = InputLimits().omega_max
        breaks = r["max_abs_omega_raw"] is not None and r["max_abs_omega_raw"] > omega_max
        chatters = r["omega_raw_tv"] is None or r["omega_raw_tv"] > CHATTER_TV
        dl = case1.get("dlsmc")
        versus = ("" if dl is None else
                  f" (DLSMC: max {_num(dl['max_abs_omega_raw'], 2)} rad/s, "
                  f"{100.0 * dl['omega_raw_over_limit']:.2f}% of steps, TV {_num(dl['omega_raw_tv'], 2)})")
        findings.append(Finding(
            "CSMC's omega chatters and breaks its limit without saturation.", breaks and chatters,
            f"CSMC before saturation: max abs omega {_num(r['max_abs_omega_raw'], 2)} rad/s, "
            f"{100.0 * r['omega_raw_over_limit']:.2f}% of steps beyond 1.59 rad/s, total "
            f"variation over the second half {_num(r['omega_raw_tv'], 2)} rad/s² (chattering "
            f"above {CHATTER_TV:g}){versus}." + ("" if breaks and chatters else
                " The search chose small switching gains P1, P2 (gains file), which leave the "
                "law nearly continuous" + ("; its omega still leaves the limit during the "
                                           "return." if breaks else
                                           ", and a slow return keeps omega inside the limit."))))
    if all(n in case2 for n in INNER_COLUMNS):
        eps = InnerLoopGains().eps
        bands = {n: case2[n]["theta_e_band"] for n in INNER_COLUMNS}
        inside = bands["dlsmc"] is not None and bands["dlsmc"] < eps
        wider = all(bands[n] is None or bands[n] > eps for n in INNER_COLUMNS[:2])
        findings.append(Finding(
            "In Case 2 the ABFSMC keeps abs(theta_e) inside epsilon while CRSMC / NTSMC "
            "settle to a wider band.", inside and wider,
            "max abs theta_e over [{:g}, {:g}) s without {:g} s after each pulse start: ".format(
                *BAND_WINDOW, PULSE_RECOVERY)
            + ", ".join(f"{_label(n)} {_num(bands[n], 5)} rad" for n in INNER_COLUMNS)
            + f" (epsilon = {eps:g} rad)." + _band_explanation(bands, eps)))
    return findings


def difference_notes(document: dict) -> list[str]:
    """Why our numbers differ from the paper's where they do, with the figures that show it."""
    case1 = document.get("case1", {}).get(CASE1_LONGITUDINAL.start_key, {})
    case2 = document.get("case2", {}).get(CASE2.start_key, {})
    notes = [
        "- **Tuning.** The DLSMC runs the paper's published gains, untuned. Every other "
        "method had its gains chosen by the same random search (budget and objective in the "
        "gains file: the Table 2 criterion itself for the position controllers), so Table 2 "
        "favours them. The paper tuned its baselines with an artificial-bee-colony optimiser "
        "and a weighting it does not publish, and does not give their laws: ours are the "
        "standard forms written in each class's docstring (boundary layers where the "
        "literature uses them). A tuned DLSMC is `config/tuned_outer.yaml` (`nfmr-tune`).",
    ]
    dl1 = case1.get("dlsmc")
    if dl1 is not None:
        notes.append(
            "- **Chattering of the cascades.** Once converged, the discrete terminal terms keep "
            "the position error at the micrometre level and theta_d = atan2(u_y, u_x) swings "
            "with it; the backward difference thetadot_d (design.md point 5) turns that into "
            f"a commanded omega beyond the limit on {100.0 * dl1['omega_raw_over_limit']:.1f}% "
            f"of the DLSMC's steps (total variation {_num(dl1['omega_raw_tv'], 0)} rad/s² over "
            "the second half). The laws with a boundary layer or no thetadot_d stay smooth. "
            "The DLSMC's `thetadot_filter` option reduces it.")
        if dl1.get("s_y_t_conv") is None and dl1.get("final_abs_s_y") is not None:
            notes.append(
                "- **s_y convergence.** Near s = 0, erf(h s) is about 1.13 h s, so the BTINTSMC "
                "reaching term k2 abs(s)^(q3/p3) erf(h s) grows like abs(s)^1.52: s_y decays "
                "algebraically, not in finite time, and after 100 s abs(s_y) is still "
                f"{1000.0 * dl1['final_abs_s_y']:.1f} mm (the paper's 6.2 s uses a threshold "
                "it does not state).")
    dl2 = case2.get("dlsmc")
    if dl2 is not None and dl2.get("theta_e_iae") is not None:
        notes.append(
            "- **Tables 3 and 4 over the whole run.** From (1, 1, pi/6) the first theta_d "
            "points about 2.4 rad away from the heading and the robot turns at the omega limit "
            f"for several seconds: that transient is most of our IAE {dl2['theta_e_iae']:.2f} "
            "rad·s. The paper's 0.0403 rad·s cannot include it, so the paper's integration "
            f"window is not the whole run; the rows from t = {BAND_WINDOW[0]:g} s compare the "
            "attitude loops once the return is over.")
    return notes


def write_report(path: Path, document: dict, figures: dict, gains_path: Path,
                 seconds: float, runs: int, jobs: int, notes: str = "") -> None:
    """Write ``report.md``."""
    case1 = document.get("case1", {})
    case2 = document.get("case2", {}).get(CASE2.start_key, {})
    long_runs = case1.get(CASE1_LONGITUDINAL.start_key, {})
    lat_runs = case1.get(CASE1_LATERAL.start_key, {})
    others = [n for n in CONTROLLER_NAMES if n not in TABLE2_COLUMNS]
    lines = [
        "# nfmr comparison report",
        "",
        "Zhang et al., *Entropy* 2023, 25(1), 27, section 4.2, reproduced with the kinematic "
        "model (3): paper sine x_d = 0.5 t, y_d = sin(0.5 x_d), 100 s at dt = 1 ms, forward "
        "Euler, inputs saturated at v in [0.2, 2] m/s, abs(omega) <= 1.59 rad/s for every "
        f"controller. Gains: `{gains_path}` (DLSMC: the paper's gains; the others tuned with "
        "the same budget, recorded in that file). "
        f"{runs} runs on {jobs} processes in {seconds:.1f} s (`nfmr-compare`).",
        "",
        "## Table 2 — Case 1, x0 = (1, 4, 0): distance error",
        "",
        *criteria_table(long_runs, TABLE2_COLUMNS, PAPER_TABLE2),
        "",
        "Controllers the paper's Table 2 does not have, same run:",
        "",
        *criteria_table(long_runs, others, {}),
        "",
        "### Convergence times, Case 1 (1, 4, 0) (section 4.2, Figs 8b, 9b, 12)",
        "",
        *convergence_table(long_runs, TABLE2_COLUMNS + tuple(others)),
        "",
        "### Every controller, Case 1 (1, 4, 0)",
        "",
        *summary_table(long_runs),
        "",
        "## Case 1, x0 = (4, 1, 0) (Fig. 7a; the paper publishes no table for it)",
        "",
        *summary_table(lat_runs),
        "",
        "## Table 3 — Case 2, x0 = (1, 1, pi/6): theta_e = theta - theta_d [rad]",
        "",
        *criteria_table(case2, INNER_COLUMNS, PAPER_TABLE3, "theta_e_"),
        "",
        f"The same criteria from t = {BAND_WINDOW[0]:g} s on (the return is over; the "
        "50 s pulse included):",
        "",
        *criteria_table(case2, INNER_COLUMNS, {}, "theta_e_settled_"),
        "",
        "## Table 4 — Case 2: theta - theta_r [rad]",
        "",
        *criteria_table(case2, INNER_COLUMNS, PAPER_TABLE4, "theta_r_"),
        "",
        f"From t = {BAND_WINDOW[0]:g} s on:",
        "",
        *criteria_table(case2, INNER_COLUMNS, {}, "theta_r_settled_"),
        "",
        "### Every controller, Case 2",
        "",
        *summary_table(case2),
        "",
        "## The paper's findings, checked",
        "",
    ]
    for finding in paper_findings(document):
        verdict = {True: "**reproduced**", False: "**not reproduced**",
                   None: "**not checked**"}[finding.reproduced]
        lines += [f"- {finding.claim} — {verdict}. {finding.evidence}", ""]
    lines += ["## Where and why the numbers differ from the paper", "",
              *difference_notes(document), ""]
    if notes:
        lines += [notes, ""]
    lines += ["## Figures", ""]
    for figure_id in sorted(figures):
        name, caption = figures[figure_id]
        lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]
    path.write_text("\n".join(lines))
