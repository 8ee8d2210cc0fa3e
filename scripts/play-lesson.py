#!/usr/bin/env python3
"""Plays one lesson of anatomy-tutor on the terminal, as a student typing answers would.

usage: play-lesson.py [--min-score S] -- COMMAND... -- ANSWER...

COMMAND runs `anatomy-tutor play LESSON ...` without --answers (the questions come on stdin).
Each ANSWER is typed at the next "answer>" prompt, except that for a question that lists numbered
choices the ANSWER is the *name* of a choice and its number, as printed, is typed. Exits 0 when
the lesson ends with every question answered and a mean score of at least S (default 1.0).
"""
import re
import subprocess
import sys


def main(argv):
    min_score = 1.0
    if argv[:1] == ["--min-score"]:
        min_score, argv = float(argv[1]), argv[2:]
    if argv[:1] != ["--"] or "--" not in argv[1:]:
        sys.exit(__doc__)
    split = argv.index("--", 1)
    command, answers = argv[1:split], argv[split + 1:]

    proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    transcript, pending, scores = "", "", []
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
            answer = answers.pop(0)
            choices = dict((name.strip(), number) for number, name in re.findall(r"^\s+(\d+)\) (.+)$", pending, re.M))
            typed = choices.get(answer, answer)
            proc.stdin.write((typed + "\n").encode())
            proc.stdin.flush()
            transcript += typed + "\n"
            pending = ""
    status = proc.wait()
    sys.stdout.write(transcript)
    scores = [float(s) for s in re.findall(r"\(score (\d+(?:\.\d+)?)\)", transcript)]
    print(f"\nplay-lesson: exit {status}, {len(scores)} questions graded, "
          f"mean score {sum(scores) / len(scores) if scores else 0:.2f}, {len(answers)} answers unused")
    if status != 0 or not scores or answers or sum(scores) / len(scores) < min_score:
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv[1:])
