# The answers that play the default course's first lesson (inner_ear) to a full score, in order,
# as scripts/play-lesson.py types them ("pick:NAME" answers a locate question by choosing the
# structure from the terminal's pick list). Sourced by test-package.sh and
# test-package-fresh-debian.sh, so both play the lesson the same way.
inner_ear_answers=(
  "pick:cochlea" Vestibule "lateral semicircular canal" "pick:superior semicircular canal" Vestibule
  "Posterior semicircular canal"
)
