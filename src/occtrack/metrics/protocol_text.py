"""The protocols' names, the numbers they report and their descriptions, apart from the
scoring code so that `occtrack eval --help` needs neither numpy nor the scoring libraries."""

PROTOCOLS = ("paper", "mot17")
KEYS = ("mota", "motp", "idf1", "hota", "mostly_tracked", "mostly_lost", "fp", "fn",
        "id_switches", "gospa", "cardinality_error")
"""The numbers every protocol reports (`evaluate`'s keys), in table order."""

SUMMARY = {
    "paper": "the paper's Table II scoring (authors' script: any pair may match, roles swapped)",
    "mot17": "the official MOTChallenge protocol, run by TrackEval (the one to quote)",
}

DESCRIPTION = {
    "paper": """\
paper: the scoring of the paper's Table II, exactly as the authors' script did it.
  Ground truth: rows with consider flag 1 and class 1, 2 or 7 (pedestrian, person on vehicle,
  static person); no visibility filter. Result: every row (rows whose class column names
  a class other than 1 are left out, with a note).
  Matching: motmetrics' accumulator with distance 1 - IoU and maximum distance 1, so ANY pair
  may match, even two boxes that do not overlap (the paper says "any degree of overlap"; its
  script let every pair match, and this follows the script).
  Roles swapped, as in the script: motmetrics is given the RESULT boxes as its objects and the
  GROUND TRUTH as its hypotheses. So MOTA = 1 - (misses + switches + false positives) / number
  of result boxes; mostly tracked / lost count result tracks matched in >= 80 % / < 20 % of
  their frames; FP is motmetrics' IDFP (ground-truth boxes the global identity matching leaves
  unmatched) and FN its IDFN (result boxes left unmatched), the two columns the script printed.
  MOTP is motmetrics' mean distance 1 - IoU of matched pairs: LOWER is better. No HOTA.
  GOSPA and cardinality use the same boxes.""",
    "mot17": """\
mot17: the official MOTChallenge protocol; MOTA, MOTP, IDF1, HOTA, MT, ML, FP, FN and ID
  switches are TrackEval's own numbers (MotChallenge2DBox preprocessing, CLEAR, Identity, HOTA).
  Result boxes matched (Hungarian, IoU >= 0.5) to a distractor (class 2, 7, 8 or 12) are
  removed; only ground truth with consider flag 1 and class 1 (pedestrian) is scored. A match
  needs IoU >= 0.5. MOTP is the mean IoU of matches: HIGHER is better. MT / ML count
  ground-truth tracks matched in > 80 % / < 20 % of their frames. HOTA is the mean over
  localisation thresholds 0.05 .. 0.95. Result rows with a class other than 1 are left out
  with a note (TrackEval refuses such files).
  GOSPA and cardinality use the mot17 pedestrian set (class 1, flag 1) and the result boxes
  left after distractor removal.""",
}

GOSPA_DESCRIPTION = """\
GOSPA: per frame with c = 1, p = 1, alpha = 2 and base distance 1 - IoU (a pair that does not
  overlap costs as much as a miss plus a false box), summed over frames. Cardinality error:
  result boxes / true boxes - 1, over all frames."""
