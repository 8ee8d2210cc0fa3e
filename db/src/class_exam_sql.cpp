// Graded exams on a class server, PostgreSQL only (a SQLite file is one person's laptop, where an
// exam is practice):
//
//  - an instructor or coordinator opens an exam for the class (at_open_exam): the items a student
//    sees go into class_exam_items (the prompt, the choices, the locate view's scene, and for
//    identify and name items the view as a picture, so that the marked structure is never named to
//    the student's machine); what grades them (the target, the key choice, the accepted names, the
//    tolerance) goes into class_exam_keys, which no login can read.
//  - a student sits it with their own login: at_start_exam starts the clock, at_answer_exam grades
//    each answer here, on the server, and writes the grade itself (the student sends an answer,
//    never a grade), at_finish_exam hands in and scores. Nothing is graded after the deadline, no
//    item is answered twice, no sitting is handed in twice.
//  - a student reads her own sitting, and her own graded answers only once she has handed in; an
//    instructor or coordinator reads the class's. Opening and closing are audited.
//
// Locate answers are graded from the structure the student's machine picked under the click (and
// its distance): the server has no label volume to pick with. Their target is in the prompt anyway.
#include "class_exam_sql.h"

namespace at::db {

std::string_view classExamSql() {
  return R"SQL(
CREATE TABLE class_exams (
  class_code    text NOT NULL REFERENCES classes(code) ON DELETE CASCADE,
  exam_id       text NOT NULL,
  course_id     text NOT NULL,
  title         text NOT NULL,
  time_limit_s  bigint NOT NULL CHECK (time_limit_s > 0),
  pass_score    double precision,
  item_count    integer NOT NULL,
  opened_by     text NOT NULL,
  opened_at     bigint NOT NULL,
  closed_at     bigint,
  PRIMARY KEY (class_code, exam_id)
);
CREATE TABLE class_exam_items (
  class_code   text NOT NULL,
  exam_id      text NOT NULL,
  position     integer NOT NULL,
  kind         text NOT NULL CHECK (kind IN ('locate', 'identify', 'name')),
  prompt       text NOT NULL,
  choices      text NOT NULL DEFAULT '[]',   -- identify: the offered structure ids, in display order
  locate_view  text NOT NULL DEFAULT '3d',
  scene        text NOT NULL DEFAULT '{}',   -- locate: the scene to pick in (it does not mark the target)
  picture      text NOT NULL DEFAULT '',     -- identify, name: the view as a base64 PNG
  PRIMARY KEY (class_code, exam_id, position),
  FOREIGN KEY (class_code, exam_id) REFERENCES class_exams(class_code, exam_id) ON DELETE CASCADE
);
CREATE TABLE class_exam_keys (
  class_code    text NOT NULL,
  exam_id       text NOT NULL,
  position      integer NOT NULL,
  question_id   text NOT NULL,
  target        text NOT NULL,
  key_choice    integer NOT NULL DEFAULT -1,
  names         text NOT NULL DEFAULT '[]',  -- name: the accepted names (JSON array)
  tolerance_mm  double precision NOT NULL DEFAULT 0,
  PRIMARY KEY (class_code, exam_id, position),
  FOREIGN KEY (class_code, exam_id, position) REFERENCES class_exam_items(class_code, exam_id, position) ON DELETE CASCADE
);
CREATE TABLE class_exam_sittings (
  class_code   text NOT NULL,
  exam_id      text NOT NULL,
  user_name    text NOT NULL,
  started_at   bigint NOT NULL,
  deadline_at  bigint NOT NULL,
  finished_at  bigint,
  score        double precision,
  passed       integer,
  PRIMARY KEY (class_code, exam_id, user_name),
  FOREIGN KEY (class_code, exam_id) REFERENCES class_exams(class_code, exam_id) ON DELETE CASCADE
);
CREATE TABLE class_exam_answers (
  class_code   text NOT NULL,
  exam_id      text NOT NULL,
  user_name    text NOT NULL,
  position     integer NOT NULL,
  answer       text NOT NULL,               -- JSON as given
  correct      integer NOT NULL,
  score        double precision NOT NULL,
  latency_ms   bigint NOT NULL DEFAULT 0,
  answered_at  bigint NOT NULL,
  PRIMARY KEY (class_code, exam_id, user_name, position),
  FOREIGN KEY (class_code, exam_id, user_name) REFERENCES class_exam_sittings(class_code, exam_id, user_name) ON DELETE CASCADE
);

-- A name as it is compared: lower case, letters and digits, single spaces, no leading "the".
CREATE FUNCTION at_exam_name(p text) RETURNS text LANGUAGE sql IMMUTABLE AS $f$
  SELECT regexp_replace(btrim(regexp_replace(lower(coalesce(p, '')), '[^a-z0-9]+', ' ', 'g')), '^the ', '')
$f$;

CREATE FUNCTION at_now() RETURNS bigint LANGUAGE sql STABLE AS $f$
  SELECT extract(epoch FROM clock_timestamp())::bigint
$f$;

-- An instructor or coordinator opens an exam for the class: p_items is a JSON array of
-- {kind, prompt, choices (array), locate_view, scene (object), picture}; p_keys one of
-- {question_id, target, key_choice, names (array), tolerance_mm}, in the same order.
CREATE FUNCTION at_open_exam(p_class text, p_exam text, p_course text, p_title text, p_limit bigint,
                             p_pass double precision, p_items text, p_keys text, p_by text)
RETURNS integer LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  r text;
  n integer;
BEGIN
  IF at_is_account() OR coalesce(p_by, '') <> '' THEN
    SELECT role INTO r FROM class_members WHERE class_code = p_class AND user_name = actor AND withdrawn_at IS NULL;
    IF r IS NULL OR r NOT IN ('instructor', 'coordinator') THEN
      RAISE EXCEPTION '''%'' is % of class %; only its instructors and coordinators open exams', actor,
        coalesce(r, 'not a member'), p_class USING ERRCODE = 'insufficient_privilege';
    END IF;
  END IF;
  IF NOT EXISTS (SELECT 1 FROM classes WHERE code = p_class) THEN
    RAISE EXCEPTION 'no class has the code %', p_class USING ERRCODE = 'no_data_found';
  END IF;
  IF EXISTS (SELECT 1 FROM class_exams WHERE class_code = p_class AND exam_id = p_exam) THEN
    RAISE EXCEPTION 'exam % was already opened in class %; its items stay as they were given', p_exam, p_class
      USING ERRCODE = 'unique_violation';
  END IF;
  n := json_array_length(p_items::json);
  IF n = 0 OR n <> json_array_length(p_keys::json) THEN
    RAISE EXCEPTION 'an exam needs items, and one key per item' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_limit IS NULL OR p_limit <= 0 THEN
    RAISE EXCEPTION 'an exam needs a time limit' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  INSERT INTO class_exams (class_code, exam_id, course_id, title, time_limit_s, pass_score, item_count, opened_by, opened_at)
  VALUES (p_class, p_exam, p_course, coalesce(p_title, p_exam), p_limit, p_pass, n, actor, at_now());
  INSERT INTO class_exam_items (class_code, exam_id, position, kind, prompt, choices, locate_view, scene, picture)
  SELECT p_class, p_exam, (i.ord - 1)::integer, i.v->>'kind', coalesce(i.v->>'prompt', ''),
         coalesce((i.v->'choices')::text, '[]'), coalesce(i.v->>'locate_view', '3d'),
         coalesce((i.v->'scene')::text, '{}'), coalesce(i.v->>'picture', '')
  FROM json_array_elements(p_items::json) WITH ORDINALITY AS i(v, ord);
  INSERT INTO class_exam_keys (class_code, exam_id, position, question_id, target, key_choice, names, tolerance_mm)
  SELECT p_class, p_exam, (k.ord - 1)::integer, coalesce(k.v->>'question_id', ''), k.v->>'target',
         coalesce((k.v->>'key_choice')::integer, -1), coalesce((k.v->'names')::text, '[]'),
         coalesce((k.v->>'tolerance_mm')::double precision, 0)
  FROM json_array_elements(p_keys::json) WITH ORDINALITY AS k(v, ord);
  PERFORM at_audit(actor, 'exam_open', p_class, p_exam, NULL, n || ' items', '');
  RETURN n;
END
$f$;

-- The sitting of the login (or, for the administrator, the member named) that may still answer:
-- started, not handed in, before its deadline. Raises otherwise.
CREATE FUNCTION at_open_sitting(p_class text, p_exam text, p_user text) RETURNS class_exam_sittings
LANGUAGE plpgsql AS $f$
DECLARE
  s class_exam_sittings%ROWTYPE;
BEGIN
  SELECT * INTO s FROM class_exam_sittings WHERE class_code = p_class AND exam_id = p_exam AND user_name = p_user
  FOR UPDATE;
  IF NOT FOUND THEN
    RAISE EXCEPTION '% has not started exam % in class %', p_user, p_exam, p_class USING ERRCODE = 'no_data_found';
  END IF;
  IF s.finished_at IS NOT NULL THEN
    RAISE EXCEPTION '% already handed in exam %', p_user, p_exam USING ERRCODE = 'insufficient_privilege';
  END IF;
  IF at_now() > s.deadline_at THEN
    RAISE EXCEPTION 'time is up for exam % (the deadline passed %s ago); nothing was graded', p_exam,
      at_now() - s.deadline_at USING ERRCODE = 'insufficient_privilege';
  END IF;
  RETURN s;
END
$f$;

-- Starts the member's sitting (the clock runs from now) or returns the one started; its deadline.
CREATE FUNCTION at_start_exam(p_class text, p_exam text, p_by text) RETURNS bigint
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  x class_exams%ROWTYPE;
  s class_exam_sittings%ROWTYPE;
BEGIN
  IF NOT EXISTS (SELECT 1 FROM class_members WHERE class_code = p_class AND user_name = actor AND withdrawn_at IS NULL) THEN
    RAISE EXCEPTION '% is not a current member of class %', actor, p_class USING ERRCODE = 'insufficient_privilege';
  END IF;
  SELECT * INTO x FROM class_exams WHERE class_code = p_class AND exam_id = p_exam;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'exam % is not open in class %', p_exam, p_class USING ERRCODE = 'no_data_found';
  END IF;
  SELECT * INTO s FROM class_exam_sittings WHERE class_code = p_class AND exam_id = p_exam AND user_name = actor;
  IF FOUND THEN RETURN s.deadline_at; END IF;
  IF x.closed_at IS NOT NULL THEN
    RAISE EXCEPTION 'exam % of class % is closed', p_exam, p_class USING ERRCODE = 'insufficient_privilege';
  END IF;
  INSERT INTO class_exam_sittings (class_code, exam_id, user_name, started_at, deadline_at)
  VALUES (p_class, p_exam, actor, at_now(), at_now() + x.time_limit_s);
  RETURN at_now() + x.time_limit_s;
END
$f$;

-- Grades one answer on the server and keeps it; returns 'saved' (never the grade). Exactly the
-- member for the item's kind is given: p_choice (identify), p_text (name), p_pick (locate: the
-- structure picked, p_distance its distance in mm or NULL).
CREATE FUNCTION at_answer_exam(p_class text, p_exam text, p_position integer, p_choice integer, p_text text,
                               p_pick text, p_distance double precision, p_latency bigint, p_by text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  s class_exam_sittings%ROWTYPE;
  i class_exam_items%ROWTYPE;
  k class_exam_keys%ROWTYPE;
  right_answer boolean;
  given json;
BEGIN
  s := at_open_sitting(p_class, p_exam, actor);
  SELECT * INTO i FROM class_exam_items WHERE class_code = p_class AND exam_id = p_exam AND position = p_position;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'exam % has no item %', p_exam, p_position + 1 USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF EXISTS (SELECT 1 FROM class_exam_answers WHERE class_code = p_class AND exam_id = p_exam AND user_name = actor
             AND position = p_position) THEN
    RAISE EXCEPTION 'item % of exam % is already answered', p_position + 1, p_exam USING ERRCODE = 'unique_violation';
  END IF;
  SELECT * INTO k FROM class_exam_keys WHERE class_code = p_class AND exam_id = p_exam AND position = p_position;
  IF i.kind = 'identify' THEN
    IF p_choice IS NULL OR p_choice < 0 OR p_choice >= json_array_length(i.choices::json) OR p_text IS NOT NULL
       OR p_pick IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for one of its % choices', p_position + 1, json_array_length(i.choices::json)
        USING ERRCODE = 'invalid_parameter_value';
    END IF;
    right_answer := p_choice = k.key_choice;
    given := json_build_object('choice', p_choice);
  ELSIF i.kind = 'name' THEN
    IF p_text IS NULL OR btrim(p_text) = '' OR p_choice IS NOT NULL OR p_pick IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for a name', p_position + 1 USING ERRCODE = 'invalid_parameter_value';
    END IF;
    right_answer := EXISTS (SELECT 1 FROM json_array_elements_text(k.names::json) AS n(name)
                            WHERE at_exam_name(n.name) = at_exam_name(p_text));
    given := json_build_object('text', p_text);
  ELSE
    IF p_pick IS NULL OR p_choice IS NOT NULL OR p_text IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for a pick', p_position + 1 USING ERRCODE = 'invalid_parameter_value';
    END IF;
    right_answer := p_pick = k.target
                    OR (k.tolerance_mm > 0 AND p_distance IS NOT NULL AND p_distance >= 0 AND p_distance <= k.tolerance_mm);
    given := json_build_object('pick', json_build_object('structure', p_pick, 'distance_mm', p_distance));
  END IF;
  INSERT INTO class_exam_answers (class_code, exam_id, user_name, position, answer, correct, score, latency_ms, answered_at)
  VALUES (p_class, p_exam, actor, p_position, given::text, CASE WHEN right_answer THEN 1 ELSE 0 END,
          CASE WHEN right_answer THEN 1 ELSE 0 END, greatest(coalesce(p_latency, 0), 0), at_now());
  RETURN 'saved';
END
$f$;

-- The positions the member has answered in their sitting (not their grades).
CREATE FUNCTION at_exam_answered(p_class text, p_exam text, p_by text) RETURNS SETOF integer
LANGUAGE sql STABLE SECURITY DEFINER AS $f$
  SELECT position FROM class_exam_answers
  WHERE class_code = p_class AND exam_id = p_exam AND user_name = at_actor(p_by) ORDER BY position
$f$;

-- Hands `p_user`'s sitting in (also after its deadline: what was answered in time counts) and
-- scores it: the mean item score, unanswered items 0. Returns the score.
CREATE FUNCTION at_hand_in(p_class text, p_exam text, p_user text) RETURNS double precision
LANGUAGE plpgsql AS $f$
DECLARE
  s class_exam_sittings%ROWTYPE;
  x class_exams%ROWTYPE;
  total double precision;
BEGIN
  SELECT * INTO s FROM class_exam_sittings WHERE class_code = p_class AND exam_id = p_exam AND user_name = p_user
  FOR UPDATE;
  IF NOT FOUND THEN
    RAISE EXCEPTION '% has not started exam % in class %', p_user, p_exam, p_class USING ERRCODE = 'no_data_found';
  END IF;
  IF s.finished_at IS NOT NULL THEN RETURN s.score; END IF;
  SELECT * INTO x FROM class_exams WHERE class_code = p_class AND exam_id = p_exam;
  SELECT coalesce(sum(score), 0) / x.item_count INTO total FROM class_exam_answers
  WHERE class_code = p_class AND exam_id = p_exam AND user_name = p_user;
  UPDATE class_exam_sittings SET finished_at = least(at_now(), deadline_at), score = total,
         passed = CASE WHEN x.pass_score IS NULL THEN NULL WHEN total >= x.pass_score THEN 1 ELSE 0 END
  WHERE class_code = p_class AND exam_id = p_exam AND user_name = p_user;
  RETURN total;
END
$f$;

-- The member hands in their own sitting.
CREATE FUNCTION at_finish_exam(p_class text, p_exam text, p_by text) RETURNS double precision
LANGUAGE plpgsql SECURITY DEFINER AS $f$
BEGIN
  RETURN at_hand_in(p_class, p_exam, at_actor(p_by));
END
$f$;

-- An instructor or coordinator closes the exam: no one starts it any more; sittings still open are
-- handed in with what they answered.
CREATE FUNCTION at_close_exam(p_class text, p_exam text, p_by text) RETURNS integer
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  r text;
  open_sitting record;
  n integer := 0;
BEGIN
  SELECT role INTO r FROM class_members WHERE class_code = p_class AND user_name = actor AND withdrawn_at IS NULL;
  IF (at_is_account() OR coalesce(p_by, '') <> '') AND (r IS NULL OR r NOT IN ('instructor', 'coordinator')) THEN
    RAISE EXCEPTION '''%'' is % of class %; only its instructors and coordinators close exams', actor,
      coalesce(r, 'not a member'), p_class USING ERRCODE = 'insufficient_privilege';
  END IF;
  UPDATE class_exams SET closed_at = at_now() WHERE class_code = p_class AND exam_id = p_exam AND closed_at IS NULL;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'exam % is not open in class %', p_exam, p_class USING ERRCODE = 'no_data_found';
  END IF;
  FOR open_sitting IN SELECT user_name FROM class_exam_sittings
                      WHERE class_code = p_class AND exam_id = p_exam AND finished_at IS NULL LOOP
    PERFORM at_hand_in(p_class, p_exam, open_sitting.user_name);
    n := n + 1;
  END LOOP;
  PERFORM at_audit(actor, 'exam_close', p_class, p_exam, 'open', 'closed', n || ' open sittings handed in');
  RETURN n;
END
$f$;

ALTER TABLE class_exams ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_exam_items ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_exam_keys ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_exam_sittings ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_exam_answers ENABLE ROW LEVEL SECURITY;
CREATE POLICY members_see_their_exams ON class_exams FOR SELECT TO at_class_member
  USING (at_role_in(class_code) IS NOT NULL);
CREATE POLICY members_see_their_items ON class_exam_items FOR SELECT TO at_class_member
  USING (at_role_in(class_code) IS NOT NULL);
CREATE POLICY own_or_taught ON class_exam_sittings FOR SELECT TO at_class_member
  USING (user_name = session_user OR at_role_in(class_code) IN ('instructor', 'coordinator'));
-- Her own grades once she handed in; the class's for its instructors and coordinators.
CREATE POLICY own_handed_in_or_taught ON class_exam_answers FOR SELECT TO at_class_member
  USING (at_role_in(class_code) IN ('instructor', 'coordinator') OR (user_name = session_user AND EXISTS (
    SELECT 1 FROM class_exam_sittings s WHERE s.class_code = class_exam_answers.class_code
      AND s.exam_id = class_exam_answers.exam_id AND s.user_name = session_user AND s.finished_at IS NOT NULL)));

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT tablename FROM pg_tables WHERE schemaname = schema_name AND tablename LIKE 'class\_exam%' LOOP
    EXECUTE format('ALTER TABLE %I.%I OWNER TO at_class_owner', schema_name, t.tablename);
    EXECUTE format('REVOKE ALL ON %I.%I FROM PUBLIC', schema_name, t.tablename);
  END LOOP;
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_exam_name', 'at_now', 'at_open_exam', 'at_open_sitting',
             'at_start_exam', 'at_answer_exam', 'at_exam_answered', 'at_hand_in', 'at_finish_exam', 'at_close_exam') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef THEN EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn); END IF;
  END LOOP;
  -- The keys are granted to no login: they are read only inside at_answer_exam.
  EXECUTE format('GRANT SELECT ON %I.class_exams, %I.class_exam_items, %I.class_exam_sittings, %I.class_exam_answers'
                 ' TO at_class_member', schema_name, schema_name, schema_name, schema_name);
END
$own$;
)SQL";
}

}  // namespace at::db
