#!/usr/bin/env python3
"""Offline search of the voice second pass's gates over a `tachi-voice-eval --dump` file (docs/voice.md,
"How the gates were chosen"). The decoding does not depend on the gates (tachi-voice-eval decodes with
none and applies them when scoring), so a dump taken once scores any gate. The decision replicates
verification_accepts() (sensor/src/voice_spotter.cpp) and the counting replicates tachi-voice-eval's
score(): per utterance, found when a kept detection names its command, WRONG when one names another;
kept detections near no utterance are false alarms. A D line's columns: run, utterance (-1: none), right, phrase,
time, score, margin, phrase_score, phrase_margin, level, garbage_score, garbage_margin, and (dumps since the garbage
ratio became an acceptance test) the phrase's seconds as the phrase grammar and as the garbage grammar align it.

  scripts/voice_gates.py DUMP [--gate margin=8 level=14 garbage_margin=0 garbage_ratio=-60 min_seconds=0.5 ...] [--search]

A phrase's own garbage ratio (phrases[].verify_min_garbage_log_ratio) is the key garbage_ratio@PHRASE, e.g.
"garbage_ratio@begin cutting=-70" (none: the top-level one).
"""
import argparse
import itertools
import json
import math
import os
import sys


def shipped_gates():
    """The gates config/voice.json ships (what tachi-voice and tachi-voice-eval use by default), read rather
    than copied here so that the two cannot drift. Keys: ratio (verify_min_log_ratio), margin, phrase_margin, level,
    garbage_margin, phrase_ratio, garbage_ratio (verify_min_garbage_log_ratio), min_seconds (verify_min_phrase_seconds)."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "config", "voice.json")
    with open(path) as f:
        c = json.load(f)
    g = dict(ratio=c["verify_min_log_ratio"], margin=c["verify_min_margin"], phrase_margin=c.get("verify_min_phrase_margin", 0.0),
             level=c.get("verify_min_level_db"), garbage_margin=c.get("verify_min_garbage_margin"),
             phrase_ratio=c.get("verify_min_phrase_log_ratio"), garbage_ratio=c.get("verify_min_garbage_log_ratio"),
             min_seconds=c.get("verify_min_phrase_seconds"))
    for p in c["phrases"]:
        if "verify_min_garbage_log_ratio" in p:
            g["garbage_ratio@" + p["phrase"]] = p["verify_min_garbage_log_ratio"]
    return g


DEFAULT = shipped_gates()


def load(path):
    runs, dets = {}, []
    for line in open(path):
        f = line.rstrip("\n").split("\t")
        if f[0] == "R":
            runs[int(f[1])] = dict(family=f[2], variant=f[3], condition=f[4], context=f[5], placed=int(f[6]), audio=float(f[7]))
        elif f[0] == "D":
            v = [float(x) for x in f[5:]]
            d = dict(run=int(f[1]), utt=int(f[2]), right=f[3] == "1", phrase=f[4], time=v[0], score=v[1], margin=v[2], phrase_score=v[3],
                     phrase_margin=v[4], level=v[5])
            d["garbage_score"] = v[6] if len(v) > 6 else math.nan
            d["garbage_margin"] = v[7] if len(v) > 7 else math.nan
            d["phrase_duration"] = v[8] if len(v) > 8 else math.nan
            d["garbage_duration"] = v[9] if len(v) > 9 else math.nan
            dets.append(d)
    return runs, dets


def ge(x, t):  # NaN compares false: refused, as in verification_accepts
    return x >= t


def accepts(g, d):
    if math.isnan(d["score"]):
        return True  # no second pass
    if not ge(d["margin"], g["margin"]):
        return False
    if g["phrase_margin"] > 0 and not ge(d["phrase_margin"], g["phrase_margin"]):
        return False
    if g["level"] is not None and not ge(d["level"], g["level"]):
        return False
    if g["garbage_margin"] is not None and not ge(d["garbage_margin"], g["garbage_margin"]):
        return False
    if g["min_seconds"] is not None and not ge(d["garbage_duration"], g["min_seconds"]):
        return False
    garbage_ratio = g["garbage_ratio"]
    if garbage_ratio is not None and g.get("garbage_ratio@" + d["phrase"]) is not None:
        garbage_ratio = g["garbage_ratio@" + d["phrase"]]
    return (d["score"] >= g["ratio"] or (garbage_ratio is not None and d["garbage_score"] >= garbage_ratio) or
            (g["phrase_ratio"] is not None and d["phrase_score"] >= g["phrase_ratio"]))


def tally(runs, dets, g):
    by_run = {}
    for d in dets:
        if accepts(g, d):
            by_run.setdefault(d["run"], []).append(d)
    t = dict(c20=0, f20=0, c20a=0, f20a=0, call=0, fall=0, wrong=0, fa_seq=0, fa_librivox=0, fa_babble=0, wrong_by={})
    for r, run in runs.items():
        kept = by_run.get(r, [])
        commanded = run["context"] in ("alone", "sentence")
        if not commanded:
            t["fa_" + run["context"]] += len(kept)
            continue
        at20 = "20 dB" in run["condition"]
        for u in range(run["placed"]):
            right = any(d["utt"] == u and d["right"] for d in kept)
            wrong = any(d["utt"] == u and not d["right"] for d in kept)
            t["call"] += 1
            t["fall"] += right
            t["wrong"] += wrong
            if wrong:
                k = run["condition"] + ", " + run["context"]
                t["wrong_by"][k] = t["wrong_by"].get(k, 0) + 1
            if at20:
                t["c20"] += 1
                t["f20"] += right
                if run["context"] == "alone":
                    t["c20a"] += 1
                    t["f20a"] += right
        t["fa_seq"] += sum(1 for d in kept if d["utt"] < 0)
    return t


def show(g, t):
    gs = " ".join(f"{k}={v}" for k, v in g.items())
    print(f"{gs}: found at 20 dB {t['f20']}/{t['c20']} = {100.0 * t['f20'] / max(1, t['c20']):.1f}% (alone {100.0 * t['f20a'] / max(1, t['c20a']):.1f}%), "
          f"all {t['fall']}/{t['call']}, WRONG {t['wrong']} {t['wrong_by']}, false alarms LibriVox {t['fa_librivox']} babble {t['fa_babble']} "
          f"amid sequences {t['fa_seq']}")


def parse_gate(items):
    g = dict(DEFAULT)
    for it in items or []:
        k, v = it.rsplit("=", 1)
        g[k] = None if v in ("none", "null") else float(v)
    return g


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dump")
    ap.add_argument("--gate", nargs="*", help="key=value overrides of the shipped gates (none: off)")
    ap.add_argument("--search", action="store_true", help="grid over margin, level, garbage margin, garbage ratio, phrase seconds")
    ap.add_argument("--max-wrong", type=int, default=0, help="--search: list gates with at most this many WRONG commands")
    a = ap.parse_args()
    runs, dets = load(a.dump)
    if not a.search:
        g = parse_gate(a.gate)
        show(g, tally(runs, dets, g))
        return
    rows = []
    for m, lv, gm, gr, sec in itertools.product([2, 4, 8], [10, 14], [None, 0, 10, 20], [None, -50, -55, -60, -65, -70, -75, -80],
                                                [None, 0.4, 0.45, 0.5, 0.55, 0.6]):
        g = dict(DEFAULT, margin=m, level=lv, garbage_margin=gm, garbage_ratio=gr, min_seconds=sec)
        t = tally(runs, dets, g)
        rows.append((g, t))
    ok = [(g, t) for g, t in rows if t["wrong"] <= a.max_wrong and t["fa_librivox"] == 0 and t["fa_babble"] == 0]
    ok.sort(key=lambda gt: (-gt[1]["f20"], gt[1]["fa_seq"]))
    for g, t in ok[:40]:
        show(g, t)


if __name__ == "__main__":
    sys.exit(main())
