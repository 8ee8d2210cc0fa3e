#!/usr/bin/env python3
"""Plays one lesson of anatomy-tutor on the terminal, as a student typing answers would.

usage: play-lesson.py [--min-score S] [--answers-dir HOST[:SEEN]] -- COMMAND... -- ANSWER...

COMMAND runs `anatomy-tutor play LESSON ...` without --answers (the questions come on stdin).
Each ANSWER is typed at the next "answer>" prompt, except that for a question that lists numbered
choices the ANSWER is the *name* of a choice and its number, as printed, is typed, and that an
ANSWER "pick:NAME" answers a locate question as a click on the structure NAME: the typed session
is left ('quit', which saves), that one answer is given through `--answers` ({"pick": NAME}), and
the lesson resumes typed. Exits 0 when the lesson ends with every question answered and the share
of answers graded right (lines starting with a check mark) is at least S (default 1.0).
--answers-dir: the folder the pick's answers file is written to (default: the temporary folder),
and, after ':', the path COMMAND sees that folder at (for a COMMAND run in a chroot, whose /tmp is
the chroot's: --answers-dir ROOT/tmp:/tmp).
"""
import json
import os
import tempfile
import re
import subprocess
import sys


def main(argv):
    min_score, answers_dir, seen_dir = 1.0, None, None
    while argv[:1] in (["--min-score"], ["--answers-dir"]):
        if argv[0] == "--min-score":
            min_score = float(argv[1])
        else:
            answers_dir, _, seen_dir = argv[1].partition(":")
        argv = argv[2:]
    if argv[:1] != ["--"] or "--" not in argv[1:]:
        sys.exit(__doc__)
    split = argv.index("--", 1)
    command, answers = argv[1:split], argv[split + 1:]

    transcript = ""
    while True:
        output, status, pick = run_typed(command, answers)
        transcript += output
        if pick is None:
            break
        with tempfile.NamedTemporaryFile("w", suffix=".jsonl", delete=False, dir=answers_dir) as f:
            f.write(json.dumps({"pick": pick, "distance_mm": 0}) + "\n")
        seen = os.path.join(seen_dir, os.path.basename(f.name)) if seen_dir else f.name
        picked = subprocess.run(command + ["--answers", seen], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        os.unlink(f.name)
        transcript += picked.stdout.decode("utf-8", "replace")
    right = len(re.findall(r"^\s*\u2713", transcript, re.M))
    wrong = len(re.findall(r"^\s*\u2717", transcript, re.M))
    graded = right + wrong
    sys.stdout.write(transcript)
    print(f"\nplay-lesson: exit {status}, {graded} answers graded, {right} right, {len(answers)} answers unused")
    if status != 0 or not graded or answers or right / graded < min_score:
        sys.exit(1)


def run_typed(command, answers):
    """Types answers until the lesson ends or the next answer is a pick; returns (output, exit
    status, the structure to pick or None)."""
    proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    transcript, pending, pick = "", "", None
    while True:
        byte = proc.stdout.read(1)
        if not byte:
            break
        char = byte.decode("utf-8", "replace") if byte[0] < 0x80 else None
        if char is None:  # a multi-byte character: read the rest of it
            raw = byte
            while True:
                try:
                    char = raw.decode("utf-8")
                    break
                except UnicodeDecodeError:
                    more = proc.stdout.read(1)
                    if not more:
                        char = raw.decode("utf-8", "replace")
                        break
                    raw += more
        transcript += char
        pending += char
        if pending.endswith("answer> "):
            if not answers:
                proc.stdin.close()
                break
            if answers[0].startswith("pick:"):
                pick = answers.pop(0)[len("pick:"):]
                proc.stdin.write(b"quit\n")
                proc.stdin.close()
                break
            answer = answers.pop(0)
            choices = dict((name.strip(), number) for number, name in re.findall(r"^\s+(\d+)\) (.+)$", pending, re.M))
            typed = choices.get(answer, answer)
            proc.stdin.write((typed + "\n").encode())
            proc.stdin.flush()
            transcript += typed + "\n"
            pending = ""
    transcript += proc.stdout.read().decode("utf-8", "replace")
    status = proc.wait()
    return transcript, status, pick

if __name__ == "__main__":
    main(sys.argv[1:])
