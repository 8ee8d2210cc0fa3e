// The schema's migrations. Released versions are frozen: never edit one, append a new one.
//
// Conventions: stable text ids for curriculum content (course, lesson, question and preset ids
// come from the course JSON, so re-seeding upserts instead of duplicating); integer ids for rows
// the program creates (datasets, users, attempts, responses); times as ISO-8601 UTC text;
// JSON documents as TEXT. No pixel data and no patient identifiers are ever stored.
#include "schema.h"

#include "class_exam_locate_sql.h"
#include "class_exam_sql.h"
#include "class_lesson_end_sql.h"
#include "class_lesson_keys_sql.h"
#include "class_security_sql.h"
#include "study_checks_sql.h"
#include "study_readers_sql.h"
#include "class_lesson_locate_sql.h"
#include "study_security_sql.h"
#include "study_writes_sql.h"

#include <algorithm>
#include <cassert>
#include <cctype>

namespace at::db {

namespace {

constexpr std::string_view kDatasets = R"SQL(
CREATE TABLE datasets (
  id               INTEGER PRIMARY KEY,
  name             TEXT NOT NULL UNIQUE,
  species          TEXT NOT NULL DEFAULT 'human',
  volume_path      TEXT NOT NULL,
  volume_checksum  TEXT NOT NULL,           -- "sha256:<hex>" of the file, or of a DICOM folder's files
  labels_path      TEXT,
  labels_checksum  TEXT,
  names_path       TEXT,
  dim_x INTEGER NOT NULL, dim_y INTEGER NOT NULL, dim_z INTEGER NOT NULL,
  spacing_x REAL NOT NULL, spacing_y REAL NOT NULL, spacing_z REAL NOT NULL,
  origin_x REAL NOT NULL, origin_y REAL NOT NULL, origin_z REAL NOT NULL,
  direction        TEXT NOT NULL,           -- JSON [9 numbers], row-major, columns = i, j, k in LPS
  orientation      TEXT NOT NULL,           -- "LPS", "RAS", …
  created_at       TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
);
CREATE TABLE structures (
  dataset_id    INTEGER NOT NULL REFERENCES datasets(id) ON DELETE CASCADE,
  label         INTEGER NOT NULL,
  structure_id  TEXT NOT NULL,
  name          TEXT NOT NULL,
  colour_r REAL NOT NULL, colour_g REAL NOT NULL, colour_b REAL NOT NULL,
  system        TEXT NOT NULL DEFAULT '',
  description   TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (dataset_id, label),
  UNIQUE (dataset_id, structure_id)
);
CREATE TABLE presets (
  id         TEXT PRIMARY KEY,
  structure  TEXT,                          -- structure id it was made for, or NULL for any
  mode       TEXT NOT NULL,
  json       TEXT NOT NULL
);
)SQL";

constexpr std::string_view kCurriculum = R"SQL(
CREATE TABLE courses (
  id        TEXT PRIMARY KEY,
  title     TEXT NOT NULL,
  summary   TEXT NOT NULL DEFAULT '',
  dataset   TEXT NOT NULL,                  -- dataset name: "phantom" or an imported dataset
  version   INTEGER NOT NULL,               -- content version; seeding replaces older content only
  synonyms  TEXT NOT NULL DEFAULT '{}',     -- JSON {structure id: [accepted names]}
  source    TEXT NOT NULL DEFAULT ''        -- file it was seeded from
);
CREATE TABLE lessons (
  id         TEXT PRIMARY KEY,
  course_id  TEXT NOT NULL REFERENCES courses(id) ON DELETE CASCADE,
  position   INTEGER NOT NULL,
  title      TEXT NOT NULL,
  summary    TEXT NOT NULL DEFAULT ''
);
CREATE INDEX lessons_by_course ON lessons(course_id, position);
CREATE TABLE lesson_prerequisites (
  lesson_id    TEXT NOT NULL REFERENCES lessons(id) ON DELETE CASCADE,
  requires_id  TEXT NOT NULL,
  position     INTEGER NOT NULL,
  PRIMARY KEY (lesson_id, requires_id)
);
CREATE TABLE questions (
  id          TEXT PRIMARY KEY,
  lesson_id   TEXT NOT NULL REFERENCES lessons(id) ON DELETE CASCADE,
  kind        TEXT NOT NULL,                -- locate, identify, name, relation, order
  target      TEXT NOT NULL,                -- structure id the question trains
  difficulty  REAL NOT NULL,                -- initial Elo difficulty from the course
  json        TEXT NOT NULL                 -- the question as in the course JSON
);
CREATE TABLE steps (
  lesson_id    TEXT NOT NULL REFERENCES lessons(id) ON DELETE CASCADE,
  position     INTEGER NOT NULL,
  kind         TEXT NOT NULL CHECK (kind IN ('show', 'question', 'study')),
  structure    TEXT NOT NULL DEFAULT '',
  preset_id    TEXT NOT NULL DEFAULT '',
  view         TEXT NOT NULL DEFAULT '',
  title        TEXT NOT NULL DEFAULT '',
  text         TEXT NOT NULL DEFAULT '',
  question_id  TEXT REFERENCES questions(id) ON DELETE CASCADE,
  study_items  TEXT NOT NULL DEFAULT '[]',  -- JSON list (study steps)
  PRIMARY KEY (lesson_id, position)
);
)SQL";

// Learner data is never deleted by re-seeding: responses keep the question id and structure as
// text, so history survives a course update that drops a question.
constexpr std::string_view kLearners = R"SQL(
CREATE TABLE users (
  id          INTEGER PRIMARY KEY,
  name        TEXT NOT NULL UNIQUE,         -- pseudonym chosen by the participant
  role        TEXT NOT NULL DEFAULT 'student' CHECK (role IN ('student', 'expert', 'coordinator')),
  group_name  TEXT NOT NULL DEFAULT '',
  created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
);
CREATE TABLE attempts (
  id           INTEGER PRIMARY KEY,
  user_id      INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  lesson_id    TEXT NOT NULL,
  mode         TEXT NOT NULL CHECK (mode IN ('guided', 'quiz_only')),
  started_at   INTEGER NOT NULL,            -- Unix seconds
  finished_at  INTEGER,                     -- NULL while in progress
  score        REAL NOT NULL DEFAULT 0      -- mean question score, set when finished
);
CREATE INDEX attempts_by_user ON attempts(user_id, lesson_id);
CREATE TABLE responses (
  id           INTEGER PRIMARY KEY,
  attempt_id   INTEGER NOT NULL REFERENCES attempts(id) ON DELETE CASCADE,
  step_index   INTEGER NOT NULL,
  question_id  TEXT NOT NULL,
  structure    TEXT NOT NULL,
  answer       TEXT NOT NULL,               -- JSON as given
  correct      INTEGER NOT NULL,
  score        REAL NOT NULL,
  latency_ms   INTEGER NOT NULL,
  preset_id    TEXT NOT NULL DEFAULT '',
  mode         TEXT NOT NULL DEFAULT '',
  t            REAL,
  alpha        REAL,
  beta         REAL,
  answered_at  INTEGER NOT NULL,            -- Unix seconds
  created_at   TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
  UNIQUE (attempt_id, step_index)
);
CREATE INDEX responses_by_question ON responses(question_id);
CREATE TABLE progress (
  user_id           INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  structure         TEXT NOT NULL,
  box               INTEGER NOT NULL,       -- Leitner box 1..5
  due_at            INTEGER NOT NULL,       -- Unix seconds
  answered          INTEGER NOT NULL,
  correct           INTEGER NOT NULL,
  last_answered_at  INTEGER NOT NULL,
  PRIMARY KEY (user_id, structure)
);
CREATE TABLE user_ability (
  user_id   INTEGER PRIMARY KEY REFERENCES users(id) ON DELETE CASCADE,
  rating    REAL NOT NULL,                  -- Elo-style ability
  answered  INTEGER NOT NULL
);
CREATE TABLE question_stats (
  question_id  TEXT PRIMARY KEY,            -- kept across re-seeding
  difficulty   REAL NOT NULL,               -- Elo difficulty learned from answers
  answered     INTEGER NOT NULL
);
)SQL";

constexpr std::string_view kStudies = R"SQL(
CREATE TABLE studies (
  id          TEXT PRIMARY KEY,
  title       TEXT NOT NULL DEFAULT '',
  dataset     TEXT NOT NULL,
  seed        INTEGER NOT NULL,              -- counterbalancing seed (Latin square permutation)
  json        TEXT NOT NULL,                 -- the protocol as stored (structures, conditions, items, scale, groups)
  created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
);
CREATE TABLE study_participants (
  study_id         TEXT NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant_id   TEXT NOT NULL,            -- pseudonymous
  group_name       TEXT NOT NULL,
  enrolment_index  INTEGER NOT NULL,         -- 0-based; selects the Latin square row
  session          INTEGER NOT NULL DEFAULT 1,
  started_at       TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
  completed_at     TEXT,
  PRIMARY KEY (study_id, participant_id),
  UNIQUE (study_id, enrolment_index)
);
CREATE TABLE study_trials (
  study_id        TEXT NOT NULL,
  participant_id  TEXT NOT NULL,
  position        INTEGER NOT NULL,          -- 0-based presentation order
  structure       TEXT NOT NULL,
  a_condition     TEXT NOT NULL,             -- the blinding: which condition was shown as A
  b_condition     TEXT NOT NULL,
  preset_a        TEXT NOT NULL,
  preset_b        TEXT NOT NULL,
  view_ms_a       REAL NOT NULL DEFAULT 0,
  view_ms_b       REAL NOT NULL DEFAULT 0,
  toggles         INTEGER NOT NULL DEFAULT 0,
  comment         TEXT,
  PRIMARY KEY (study_id, participant_id, position),
  FOREIGN KEY (study_id, participant_id) REFERENCES study_participants(study_id, participant_id) ON DELETE CASCADE
);
CREATE TABLE study_ratings (
  study_id        TEXT NOT NULL,
  participant_id  TEXT NOT NULL,
  position        INTEGER NOT NULL,
  item            TEXT NOT NULL,
  rating_ab       INTEGER NOT NULL,          -- as shown: 1 = prefer A ... 5 = prefer B
  response_ms     REAL NOT NULL DEFAULT 0,
  t               REAL NOT NULL DEFAULT 0,
  alpha           REAL NOT NULL DEFAULT 0,
  beta            REAL NOT NULL DEFAULT 0,
  app_version     TEXT NOT NULL DEFAULT '',
  created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
  PRIMARY KEY (study_id, participant_id, position, item),
  FOREIGN KEY (study_id, participant_id, position)
    REFERENCES study_trials(study_id, participant_id, position) ON DELETE CASCADE
);
)SQL";

// Answers to review questions, asked outside any lesson attempt: the same columns as responses,
// keyed by the user instead of an attempt. They move progress, ability and question difficulty
// like lesson answers (one transaction per answer).
constexpr std::string_view kReviews = R"SQL(
CREATE TABLE review_responses (
  id           INTEGER PRIMARY KEY,
  user_id      INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  question_id  TEXT NOT NULL,
  structure    TEXT NOT NULL,
  answer       TEXT NOT NULL,               -- JSON as given
  correct      INTEGER NOT NULL,
  score        REAL NOT NULL,
  latency_ms   INTEGER NOT NULL,
  preset_id    TEXT NOT NULL DEFAULT '',
  mode         TEXT NOT NULL DEFAULT '',
  t            REAL,
  alpha        REAL,
  beta         REAL,
  answered_at  INTEGER NOT NULL,            -- Unix seconds
  created_at   TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
);
CREATE INDEX review_responses_by_user ON review_responses(user_id, id);
CREATE INDEX review_responses_by_question ON review_responses(question_id);
)SQL";

// FSRS replaces the Leitner boxes (lessons/fsrs.h). Each structure's box becomes a memory state
// that keeps the student's schedule: the due time stays; the stability is the interval the box
// stood for (at 90 % desired retention FSRS's interval equals the stability), 1, 2, 4, 8 or 16
// days, except box 1 (the last answer wrong) which takes w0 = 0.212 days, the stability of a
// first Again, and is Relearning (Learning if never right); the difficulty goes from D0(Good) =
// 2.1181 to D0(Again) = 6.4133 with the share of wrong answers. The Leitner table is kept, renamed,
// as it was. Every earlier answer (lesson and review) is copied into the review log, rated from its
// grade (right: Good, wrong with at least half credit: Hard, else Again) and marked rebuilt.
constexpr std::string_view kFsrs = R"SQL(
CREATE TABLE memory_states (
  user_id         INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  structure       TEXT NOT NULL,
  phase           TEXT NOT NULL CHECK (phase IN ('learning', 'review', 'relearning')),
  step            INTEGER NOT NULL DEFAULT 0,  -- index into the (re)learning steps
  stability       REAL NOT NULL,               -- days
  difficulty      REAL NOT NULL,               -- 1..10
  due_at          INTEGER NOT NULL,            -- Unix seconds
  last_review_at  INTEGER NOT NULL,            -- Unix seconds
  reviews         INTEGER NOT NULL,
  lapses          INTEGER NOT NULL DEFAULT 0,
  answered        INTEGER NOT NULL,
  correct         INTEGER NOT NULL,
  PRIMARY KEY (user_id, structure)
);
INSERT INTO memory_states (user_id, structure, phase, step, stability, difficulty, due_at, last_review_at,
                           reviews, lapses, answered, correct)
SELECT user_id, structure,
       CASE WHEN box >= 2 THEN 'review' WHEN correct > 0 THEN 'relearning' ELSE 'learning' END,
       0,
       CASE WHEN box <= 1 THEN 0.212 WHEN box = 2 THEN 2.0 WHEN box = 3 THEN 4.0 WHEN box = 4 THEN 8.0 ELSE 16.0 END,
       min(10.0, max(1.0, 2.11810397 + (6.4133 - 2.11810397) * (answered - correct) / max(answered, 1.0))),
       due_at, last_answered_at, answered, 0, answered, correct
FROM progress WHERE answered > 0;
ALTER TABLE progress RENAME TO leitner_progress;

CREATE TABLE review_log (
  id            INTEGER PRIMARY KEY,
  user_id       INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  structure     TEXT NOT NULL,
  question_id   TEXT NOT NULL,
  source        TEXT NOT NULL CHECK (source IN ('lesson', 'review', 'exam')),
  source_id     INTEGER,                     -- the answer's row in responses / review_responses / exam_items
  reviewed_at   INTEGER NOT NULL,            -- Unix seconds
  rating        INTEGER NOT NULL CHECK (rating BETWEEN 1 AND 4),  -- again, hard, good, easy
  correct       INTEGER NOT NULL,
  score         REAL NOT NULL,
  latency_ms    INTEGER NOT NULL,            -- 0 = not measured
  phase_before  TEXT NOT NULL DEFAULT 'new', -- memory phase before the answer
  elapsed_days  INTEGER,                     -- whole days since the previous answer; NULL for the first
  phase_after   TEXT,                        -- memory state after the answer (NULL when rebuilt)
  stability     REAL,
  difficulty    REAL,
  due_at        INTEGER,
  rebuilt       INTEGER NOT NULL DEFAULT 0   -- 1: copied from an answer given before FSRS
);
CREATE INDEX review_log_by_user ON review_log(user_id, structure, reviewed_at);
INSERT INTO review_log (user_id, structure, question_id, source, source_id, reviewed_at, rating, correct, score,
                        latency_ms, rebuilt)
SELECT user_id, structure, question_id, source, source_id, answered_at,
       CASE WHEN correct <> 0 THEN 3 WHEN score >= 0.5 THEN 2 ELSE 1 END, correct, score, latency_ms, 1
FROM (SELECT a.user_id, r.structure, r.question_id, 'lesson' AS source, r.id AS source_id, r.answered_at,
             r.correct, r.score, r.latency_ms
      FROM responses r JOIN attempts a ON a.id = r.attempt_id
      UNION ALL
      SELECT user_id, structure, question_id, 'review', id, answered_at, correct, score, latency_ms
      FROM review_responses)
ORDER BY answered_at, source, source_id;
)SQL";

// Practical exams: their definitions from the course (replaced on re-seeding like lessons), and
// the students' attempts with every drawn item, its answer and grade (kept across re-seeding).
constexpr std::string_view kExams = R"SQL(
CREATE TABLE exams (
  id         TEXT PRIMARY KEY,
  course_id  TEXT NOT NULL REFERENCES courses(id) ON DELETE CASCADE,
  position   INTEGER NOT NULL,
  json       TEXT NOT NULL                  -- the exam as in the course JSON
);
CREATE TABLE exam_attempts (
  id           INTEGER PRIMARY KEY,
  user_id      INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
  exam_id      TEXT NOT NULL,
  course_id    TEXT NOT NULL,
  started_at   INTEGER NOT NULL,            -- Unix seconds
  deadline_at  INTEGER NOT NULL,            -- started_at + the time limit
  finished_at  INTEGER,                     -- NULL while in progress
  score        REAL,                        -- mean item score, unanswered = 0
  passed       INTEGER                      -- NULL when the exam has no pass score
);
CREATE INDEX exam_attempts_by_user ON exam_attempts(user_id, exam_id);
CREATE TABLE exam_items (
  id           INTEGER PRIMARY KEY,
  attempt_id   INTEGER NOT NULL REFERENCES exam_attempts(id) ON DELETE CASCADE,
  position     INTEGER NOT NULL,
  question_id  TEXT NOT NULL,
  kind         TEXT NOT NULL,
  structure    TEXT NOT NULL,               -- the item's target
  question     TEXT NOT NULL,               -- the generated question (course question JSON)
  choices      TEXT NOT NULL DEFAULT '[]',  -- JSON: offered structure ids (identify), in display order
  key_choice   INTEGER NOT NULL DEFAULT -1,
  locate_view  TEXT NOT NULL DEFAULT '3d',
  scene        TEXT NOT NULL,               -- JSON {structure, preset, view}
  answer       TEXT,                        -- JSON as given; NULL = not answered
  correct      INTEGER,
  score        REAL,
  latency_ms   INTEGER,
  answered_at  INTEGER,
  UNIQUE (attempt_id, position)
);
)SQL";

// Study ratings remember the participant's session they were given in (before, every row showed
// the participant's latest session). Ratings given when the participant had one session so far
// are from session 1; for the others the session is not known (NULL, exported blank). Trials
// remember whether their viewing times were measured (the desktop runner) or the two views were
// shown as files outside the program (the terminal runner: times not known).
constexpr std::string_view kStudySessions = R"SQL(
ALTER TABLE study_ratings ADD COLUMN session INTEGER;
UPDATE study_ratings SET session = 1
WHERE (SELECT p.session FROM study_participants p
       WHERE p.study_id = study_ratings.study_id AND p.participant_id = study_ratings.participant_id) = 1;
ALTER TABLE study_trials ADD COLUMN viewing_measured INTEGER NOT NULL DEFAULT 1;
)SQL";

// How an imported dataset's files are read (import --skip-unreadable, --nrrd-data, --intensity,
// --intercept, --slope; a package's modality), kept so that every later open reads them the same
// way: JSON {"skip_unreadable": true, "data_folder": "/abs", "intensity": "plain", "intercept": -1024,
// "slope": 1, "modality": "MR"}, each key only where it is set.
constexpr std::string_view kDatasetLoadOptions = R"SQL(
ALTER TABLE datasets ADD COLUMN load_options TEXT;
)SQL";

// A class on a class server, and the learning records its students' machines send there.
// On the server: classes (joined with their code), their members with a role, and class_events —
// every answer, lesson start and lesson end any member's machine sent, once (its UUID is the key;
// append-only: what the instructor sees is computed from them). On a learner's machine: the
// class each local user joined (class_memberships) and the outbox — the same events, written in
// the transaction that records them locally and marked sent once the server has them.
constexpr std::string_view kClasses = R"SQL(
CREATE TABLE classes (
  code        TEXT PRIMARY KEY,          -- what members type to join (8 letters and digits)
  title       TEXT NOT NULL,
  created_by  TEXT NOT NULL,
  created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
);
CREATE TABLE class_members (
  class_code  TEXT NOT NULL REFERENCES classes(code) ON DELETE CASCADE,
  user_name   TEXT NOT NULL,
  role        TEXT NOT NULL CHECK (role IN ('student', 'instructor', 'coordinator')),
  joined_at   INTEGER NOT NULL,          -- Unix seconds
  PRIMARY KEY (class_code, user_name)
);
CREATE TABLE class_events (
  uuid        TEXT PRIMARY KEY,          -- minted by the learner's machine when the event happened
  class_code  TEXT NOT NULL REFERENCES classes(code) ON DELETE CASCADE,
  user_name   TEXT NOT NULL,
  kind        TEXT NOT NULL CHECK (kind IN ('answer', 'lesson_started', 'lesson_finished')),
  occurred_at INTEGER NOT NULL,          -- Unix seconds on the learner's machine
  lesson_id   TEXT NOT NULL DEFAULT '',
  question_id TEXT NOT NULL DEFAULT '',
  structure   TEXT NOT NULL DEFAULT '',
  correct     INTEGER,                   -- answers: 1 right, 0 wrong
  score       REAL,                      -- answers: the grade; lesson_finished: the lesson's score
  payload     TEXT NOT NULL DEFAULT '{}',-- the whole record as JSON (outbox.h)
  received_at INTEGER NOT NULL
);
CREATE INDEX class_events_by_member ON class_events(class_code, user_name, occurred_at);
CREATE TABLE class_memberships (
  user_name   TEXT PRIMARY KEY,          -- a local user; one class at a time
  class_code  TEXT NOT NULL,
  server      TEXT NOT NULL,             -- the class server's URL, as given to `class join`
  role        TEXT NOT NULL,
  joined_at   INTEGER NOT NULL
);
CREATE TABLE outbox (
  seq         INTEGER PRIMARY KEY,       -- the order events happened in on this machine
  uuid        TEXT NOT NULL UNIQUE,
  server      TEXT NOT NULL,
  class_code  TEXT NOT NULL,
  user_name   TEXT NOT NULL,
  kind        TEXT NOT NULL,
  occurred_at INTEGER NOT NULL,
  lesson_id   TEXT NOT NULL DEFAULT '',
  question_id TEXT NOT NULL DEFAULT '',
  structure   TEXT NOT NULL DEFAULT '',
  correct     INTEGER,
  score       REAL,
  payload     TEXT NOT NULL DEFAULT '{}',
  sent_at     INTEGER                    -- NULL until the server has it
);
CREATE INDEX outbox_unsent ON outbox(server, sent_at, seq);
)SQL";

// What a participant saw when rating: the render quality level on screen (the full
// level is quality_full_level; NULL: not known, e.g. rated without a view or before this version),
// the full level's resolution as a share of the view, and the milliseconds from the rated side
// being shown to the full level being on screen.
constexpr std::string_view kStudyRatingQuality = R"SQL(
ALTER TABLE study_ratings ADD COLUMN quality_level INTEGER;
ALTER TABLE study_ratings ADD COLUMN quality_full_level INTEGER;
ALTER TABLE study_ratings ADD COLUMN quality_scale REAL;
ALTER TABLE study_ratings ADD COLUMN settle_ms REAL;
)SQL";

// A course step's free camera and clipping plane (course JSON's "camera" and "clip" as one JSON
// object, lessons::placementToJson); NULL: the step frames its named view, unclipped.
constexpr std::string_view kStepPlacement = R"SQL(
ALTER TABLE steps ADD COLUMN placement TEXT;
)SQL";

// An instructor's review of each structure's labels (the segment editor's structures list):
// db::ReviewState's names. Instructor metadata: never part of what students are shown.
constexpr std::string_view kStructureReview = R"SQL(
ALTER TABLE structures ADD COLUMN review_state TEXT NOT NULL DEFAULT 'not_started'
  CHECK (review_state IN ('not_started', 'in_progress', 'completed', 'flagged'));
)SQL";

// Withdrawal and exclusion of class members (the reason kept; their events stay), the audit of
// every role change, withdrawal and correction on a class server (who: the acting name and the
// login; when; old and new value), and the outbox's refusals: the server's reason for an event it
// did not count (the event is not sent again).
constexpr std::string_view kClassAudit = R"SQL(
ALTER TABLE class_members ADD COLUMN withdrawn_at INTEGER;
ALTER TABLE class_members ADD COLUMN withdrawal_reason TEXT;
ALTER TABLE outbox ADD COLUMN refused TEXT;
CREATE TABLE class_audit (
  id           INTEGER PRIMARY KEY,
  recorded_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
  actor        TEXT NOT NULL,             -- the member who acted
  login        TEXT NOT NULL,             -- the server login it came through
  action       TEXT NOT NULL,             -- account, member, role, withdraw, correct
  class_code   TEXT NOT NULL DEFAULT '',
  target       TEXT NOT NULL DEFAULT '',  -- the member (and event) it changed
  old_value    TEXT,
  new_value    TEXT,
  reason       TEXT NOT NULL DEFAULT ''
);
)SQL";

// A trial's viewing times are blank (NULL) when they were not measured (the views were shown as
// files outside the program), not 0: a reader cannot mistake them for a participant who looked
// for no time at all. SQLite cannot drop NOT NULL in place, so there the columns are rebuilt as
// nullable ones; PostgreSQL drops the constraint in place, which keeps the table's owner
// (at_class_owner after the class server's security), its grants and its row-level security.
constexpr std::string_view kUnmeasuredViewingBlank = R"SQL(
ALTER TABLE study_trials ADD COLUMN view_ms_a_measured REAL;
ALTER TABLE study_trials ADD COLUMN view_ms_b_measured REAL;
UPDATE study_trials SET view_ms_a_measured = view_ms_a, view_ms_b_measured = view_ms_b WHERE viewing_measured = 1;
ALTER TABLE study_trials DROP COLUMN view_ms_a;
ALTER TABLE study_trials DROP COLUMN view_ms_b;
ALTER TABLE study_trials RENAME COLUMN view_ms_a_measured TO view_ms_a;
ALTER TABLE study_trials RENAME COLUMN view_ms_b_measured TO view_ms_b;
)SQL";
constexpr std::string_view kUnmeasuredViewingBlankPostgres = R"SQL(
ALTER TABLE study_trials ALTER COLUMN view_ms_a DROP NOT NULL, ALTER COLUMN view_ms_b DROP NOT NULL;
UPDATE study_trials SET view_ms_a = NULL, view_ms_b = NULL WHERE viewing_measured <> 1;
)SQL";

// A study's owner (the coordinator's login on a class server; '' = whoever administers the
// database) and its participants' withdrawal (consent withdrawn) or exclusion: when, which, why.
// Their rows stay; exports and Table 2 leave them out. next_enrolment: the study's next
// counterbalancing row, drawn by enrolment (at least the participants' highest row + 1, so rows
// merged in from other machines are never drawn again).
constexpr std::string_view kStudyOwnersAndWithdrawals = R"SQL(
ALTER TABLE studies ADD COLUMN owner TEXT NOT NULL DEFAULT '';
ALTER TABLE studies ADD COLUMN next_enrolment INTEGER NOT NULL DEFAULT 0;
ALTER TABLE study_participants ADD COLUMN withdrawn_at TEXT;
ALTER TABLE study_participants ADD COLUMN withdrawal_kind TEXT CHECK (withdrawal_kind IN ('withdrawn', 'excluded'));
ALTER TABLE study_participants ADD COLUMN withdrawal_reason TEXT;
)SQL";
}  // namespace

const std::vector<Migration>& migrations() {
  static const std::vector<Migration> all = {
      {1, "datasets, structures and presets", kDatasets},
      {2, "courses, lessons, prerequisites, steps and questions", kCurriculum},
      {3, "users, attempts, responses, progress, ability and question difficulty", kLearners},
      {4, "preference studies: protocols, participants, blinded trials, ratings", kStudies},
      {5, "review responses: answers to review questions outside lesson attempts", kReviews},
      {6, "FSRS memory states (from the Leitner boxes) and the review log", kFsrs,
       {{"min(10.0, max(1.0, ", "LEAST(10.0, GREATEST(1.0, "},
        {"/ max(answered, 1.0)", "/ GREATEST(answered, 1.0)"},
        {"FROM review_responses)\nORDER BY", "FROM review_responses) AS earlier_answers\nORDER BY"}}},
      {7, "practical exams: definitions, attempts and their items", kExams},
      {8, "study ratings keep their session; trials say whether viewing was measured", kStudySessions},
      {9, "how an imported dataset's files are read (skip unreadable files, data folder)", kDatasetLoadOptions},
      {10, "class server: classes, members and roles, learning events; a learner's class membership and outbox", kClasses},
      {11, "study ratings record the render quality on screen and its settle time", kStudyRatingQuality},
      {12, "course steps keep a free camera and a clipping plane", kStepPlacement},
      {13, "structures keep their review state (not started, in progress, completed, flagged)", kStructureReview},
      {14, "class members can be withdrawn; an audit of class changes; the outbox keeps refusals", kClassAudit},
      {15, "class server security: owner role, one login per person, row-level security, audited functions",
       classSecuritySql(), {}, true},
      {16, "study trials: viewing times not measured are blank (NULL), not 0", kUnmeasuredViewingBlank, {}, false,
       kUnmeasuredViewingBlankPostgres},
      {17, "class server: graded exams, their keys readable by no login, graded and scored by the server",
       classExamSql(), {}, true},
      {18, "studies have an owner and draw enrolment rows from a counter; participants can be withdrawn or excluded",
       kStudyOwnersAndWithdrawals},
      {19, "class server: a study's owner reads it, withdraws and excludes its participants (audited)",
       studySecuritySql(), {}, true},
      {20, "class server: locate items graded from the pixel clicked on their picture; exam prerequisites checked there",
       classExamLocateSql(), {}, true},
      {21, "class server: a study's coordinator registers it and records its participants through audited functions",
       studyWritesSql(), {}, true},
      {22, "class server: lesson answers graded there from the class's published keys, not as the laptop sent them",
       classLessonKeysSql(), {}, true},
      {23, "class server: study writes need a current coordinator; a participant's trials must be the row the server drew",
       studyChecksSql(), {}, true},
      {24, "class server: a study's owner reads it only while she coordinates a class",
       studyReadersSql(), {}, true},
      {25, "class server: lesson locate answers graded from the pixel picked on the question's view, else kept as practice",
       classLessonLocateSqliteSql(), {}, false, classLessonLocateSql()},
      {26, "class server: a lesson's end scored again, and audited, when its answers are graded again",
       classLessonEndSql(), {}, true},
  };
  return all;
}

int latestSchemaVersion() { return int(migrations().size()); }

namespace {

bool wordChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Replaces whole-word occurrences of `word` outside quoted text.
std::string replaceWord(const std::string& text, std::string_view word, std::string_view by) {
  std::string out;
  char quote = 0;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '-' && i + 1 < text.size() && text[i + 1] == '-') {  // a comment, to the end of its line
      const std::size_t end = std::min(text.find('\n', i), text.size());
      out.append(text, i, end - i);
      i = end;
      continue;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (text.compare(i, word.size(), word) == 0 && (i == 0 || !wordChar(text[i - 1])) &&
               (i + word.size() >= text.size() || !wordChar(text[i + word.size()]))) {
      out += by;
      i += word.size();
      continue;
    }
    out += c;
    ++i;
  }
  return out;
}

std::string replaceAll(std::string text, std::string_view from, std::string_view to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

}  // namespace

std::string postgresDdl(std::string_view sqliteSql) {
  std::string s = replaceAll(std::string(sqliteSql), "INTEGER PRIMARY KEY", "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY");
  s = replaceWord(s, "INTEGER", "BIGINT");
  s = replaceWord(s, "REAL", "DOUBLE PRECISION");
  return replaceAll(s, "(strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))",
                    "(to_char(clock_timestamp() AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T\"HH24:MI:SS.MS\"Z\"'))");
}

std::string migrationSql(const Migration& migration, Backend backend) {
  if (backend == Backend::Postgres && !migration.postgresSql.empty()) return std::string(migration.postgresSql);
  if (migration.postgresOnly) return backend == Backend::Postgres ? std::string(migration.sql) : std::string();
  if (backend == Backend::Sqlite) return std::string(migration.sql);
  std::string s = postgresDdl(migration.sql);
  for (const auto& [from, to] : migration.postgresEdits) {
    const auto at = s.find(from);
    assert(at != std::string::npos && "a PostgreSQL edit of a migration must match its text");
    if (at != std::string::npos) s.replace(at, from.size(), to);
  }
  return s;
}

}  // namespace at::db
