// Graded exams decide locate answers and prerequisites on the server (PostgreSQL only):
//
//  - a locate item is sent to the student as a picture of its fixed view (picture_width ×
//    picture_height); its key is the set of that picture's pixels whose click counts, as runs of
//    a row (class_exam_locate_keys: y, x_from..x_to inclusive), computed on the instructor's
//    machine by the laptop's own grader for every pixel (the structure under the click, or within
//    the item's tolerance of the target). No login can read the runs.
//  - the student sends the pixel clicked, never a structure or a grade: at_answer_exam looks the
//    pixel up in the runs. A pixel outside the picture is refused.
//  - a name item is graded by the laptop's rule (quiz/sided_names.h, quiz::gradeName): the key
//    keeps the target's spellings without their side words and the other structures' (normalised
//    on the instructor's machine by quiz::splitSide), the target's side and whether it is asked;
//    the server folds the typed text the same way (at_fold_name, at_split_side), forgives a typo
//    within quiz::typoAllowance (restricted Damerau–Levenshtein on bytes) unless another
//    structure's spelling is as close, and gives 0.5 for a missing side, 0.25 for the wrong one.
//  - an exam keeps the lessons to finish before it (class_exams.prerequisites, a JSON array of
//    lesson ids); at_start_exam refuses a member who has not finished them on the server (a
//    lesson_finished event the server accepted, at_record_event).
#include "class_exam_locate_sql.h"

namespace at::db {

std::string_view classExamLocateSql() {
  return R"SQL(
ALTER TABLE class_exams ADD COLUMN prerequisites text NOT NULL DEFAULT '[]';
ALTER TABLE class_exam_items ADD COLUMN picture_width integer NOT NULL DEFAULT 0;
ALTER TABLE class_exam_items ADD COLUMN picture_height integer NOT NULL DEFAULT 0;
CREATE TABLE class_exam_locate_keys (
  class_code  text NOT NULL,
  exam_id     text NOT NULL,
  position    integer NOT NULL,
  y           integer NOT NULL,
  x_from      integer NOT NULL,
  x_to        integer NOT NULL CHECK (x_to >= x_from),
  PRIMARY KEY (class_code, exam_id, position, y, x_from),
  FOREIGN KEY (class_code, exam_id, position) REFERENCES class_exam_keys(class_code, exam_id, position) ON DELETE CASCADE
);
ALTER TABLE class_exam_locate_keys ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_exam_keys ADD COLUMN name_bodies text NOT NULL DEFAULT '[]';       -- JSON array
ALTER TABLE class_exam_keys ADD COLUMN competitor_bodies text NOT NULL DEFAULT '[]'; -- JSON array
ALTER TABLE class_exam_keys ADD COLUMN target_side text NOT NULL DEFAULT '' CHECK (target_side IN ('', 'left', 'right'));
ALTER TABLE class_exam_keys ADD COLUMN ask_side boolean NOT NULL DEFAULT false;

-- quiz::normalizeName's character folding: ASCII letters to lower case, Latin-1 and Latin
-- Extended-A letters to ASCII (the same tables; 1 = ij, 2 = oe, 3 = ae, 4 = th, 5 = ss), combining
-- marks dropped, every other character below U+0180 and general punctuation (U+2000–U+206F) a
-- space; other scripts kept.
CREATE FUNCTION at_fold_name(p text) RETURNS text LANGUAGE sql IMMUTABLE AS $f$
  SELECT replace(replace(replace(replace(replace(
           regexp_replace(regexp_replace(
             translate(coalesce(p, ''),
                       'ABCDEFGHIJKLMNOPQRSTUVWXYZ' || (SELECT string_agg(chr(c), '' ORDER BY c) FROM generate_series(192, 383) c),
                       'abcdefghijklmnopqrstuvwxyz' || translate(
                         'aaaaaa3ceeeeiiiidnooooo ouuuuy45aaaaaa3ceeeeiiiidnooooo ouuuuy4y'
                         'aaaaaaccccccccddddeeeeeeeeeegggggggghhhhiiiiiiiiii11jjkkkllllllllllnnnnnnnnnoooooo22rrrrrrssssssss'
                         'ttttttuuuuuuuuuuuuwwyyyzzzzzzs',
                         '12345', chr(57345) || chr(57346) || chr(57347) || chr(57348) || chr(57349))),
             '[\u0300-\u036f]', '', 'g'),
           '[\u0001-\u002f\u003a-\u0060\u007b-\u00bf\u2000-\u206f\ufffd]', ' ', 'g'),
         chr(57345), 'ij'), chr(57346), 'oe'), chr(57347), 'ae'), chr(57348), 'th'), chr(57349), 'ss')
$f$;

-- quiz::splitSide of a typed name: its words without articles and side words (l, left, r, right),
-- and the side they gave ('' when none, or both: then conflicting).
CREATE FUNCTION at_split_side(p text, OUT body text, OUT side text, OUT conflicting boolean)
LANGUAGE sql IMMUTABLE AS $f$
  SELECT coalesce(string_agg(w, ' ' ORDER BY n) FILTER (WHERE w NOT IN ('left', 'l', 'right', 'r')), ''),
         CASE WHEN coalesce(bool_or(w IN ('left', 'l')), false) = coalesce(bool_or(w IN ('right', 'r')), false) THEN ''
              WHEN bool_or(w IN ('left', 'l')) THEN 'left' ELSE 'right' END,
         coalesce(bool_or(w IN ('left', 'l')) AND bool_or(w IN ('right', 'r')), false)
  FROM regexp_split_to_table(btrim(at_fold_name(p)), '\s+') WITH ORDINALITY AS t(w, n)
  WHERE w <> '' AND w NOT IN ('the', 'a', 'an')
$f$;

-- quiz::damerauLevenshtein: optimal string alignment distance on the UTF-8 bytes.
CREATE FUNCTION at_osa_distance(p_a text, p_b text) RETURNS integer LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  a bytea := convert_to(p_a, 'UTF8');
  b bytea := convert_to(p_b, 'UTF8');
  n integer := length(a);
  m integer := length(b);
  d integer[];
  w integer := m + 1;
  cost integer;
  v integer;
BEGIN
  IF n = 0 THEN RETURN m; END IF;
  IF m = 0 THEN RETURN n; END IF;
  d := array_fill(0, ARRAY[(n + 1) * w]);
  FOR i IN 0..n LOOP d[i * w + 1] := i; END LOOP;
  FOR j IN 0..m LOOP d[j + 1] := j; END LOOP;
  FOR i IN 1..n LOOP
    FOR j IN 1..m LOOP
      cost := CASE WHEN get_byte(a, i - 1) = get_byte(b, j - 1) THEN 0 ELSE 1 END;
      v := least(d[(i - 1) * w + j + 1] + 1, d[i * w + j] + 1, d[(i - 1) * w + j] + cost);
      IF i > 1 AND j > 1 AND get_byte(a, i - 1) = get_byte(b, j - 2) AND get_byte(a, i - 2) = get_byte(b, j - 1) THEN
        v := least(v, d[(i - 2) * w + j - 1] + 1);
      END IF;
      d[i * w + j + 1] := v;
    END LOOP;
  END LOOP;
  RETURN d[n * w + m + 1];
END
$f$;

-- quiz::typoAllowance: the edit distance forgiven in a spelling of n bytes.
CREATE FUNCTION at_typo_allowance(n integer) RETURNS integer LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE WHEN n <= 4 THEN 0 WHEN n <= 8 THEN 1 WHEN n <= 16 THEN 2 ELSE 3 END
$f$;

-- quiz::gradeName's score for `p_typed` against a key: 1 right; with the side asked 0.5 for none,
-- 0.25 for the other one; 0 for another name, or a typo as close to another structure's.
CREATE FUNCTION at_grade_name(p_typed text, p_bodies text, p_competitors text, p_side text, p_ask_side boolean)
RETURNS double precision LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  typed record;
  best integer;
  best_length integer;
  dist integer;
  body text;
BEGIN
  SELECT * INTO typed FROM at_split_side(p_typed);
  IF typed.body = '' THEN RETURN 0; END IF;
  FOR body IN SELECT b FROM json_array_elements_text(p_bodies::json) WITH ORDINALITY AS t(b, n) WHERE b <> '' ORDER BY n LOOP
    dist := at_osa_distance(typed.body, body);
    IF best IS NULL OR dist < best THEN
      best := dist;
      best_length := octet_length(body);
    END IF;
  END LOOP;
  IF best IS NULL THEN RETURN 0; END IF;
  IF best > 0 THEN
    IF best > at_typo_allowance(best_length) THEN RETURN 0; END IF;
    -- A typo is forgiven only when no other structure's spelling is as close (the length
    -- difference bounds the distance from below).
    IF EXISTS (SELECT 1 FROM json_array_elements_text(p_competitors::json) AS c(b)
               WHERE c.b <> '' AND abs(octet_length(c.b) - octet_length(typed.body)) <= best
                 AND at_osa_distance(typed.body, c.b) <= best) THEN
      RETURN 0;
    END IF;
  END IF;
  IF NOT p_ask_side OR coalesce(p_side, '') = '' THEN RETURN 1; END IF;
  IF typed.side = p_side AND NOT typed.conflicting THEN RETURN 1; END IF;
  IF typed.side = '' THEN RETURN 0.5; END IF;
  RETURN 0.25;
END
$f$;

DROP FUNCTION at_open_exam(text, text, text, text, bigint, double precision, text, text, text);
DROP FUNCTION at_answer_exam(text, text, integer, integer, text, text, double precision, bigint, text);

-- An instructor or coordinator opens an exam for the class: p_items is a JSON array of
-- {kind, prompt, choices (array), locate_view, scene (object), picture, picture_width,
-- picture_height}; p_keys one of {question_id, target, key_choice, names (array), tolerance_mm,
-- accepted_pixels (locate: array of [y, x_from, x_to])}, in the same order; p_prerequisites a JSON
-- array of the lesson ids to finish first.
CREATE FUNCTION at_open_exam(p_class text, p_exam text, p_course text, p_title text, p_limit bigint,
                             p_pass double precision, p_items text, p_keys text, p_prerequisites text, p_by text)
RETURNS integer LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  r text;
  n integer;
  bad integer;
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
  -- A locate item is answered on its picture: it needs one, and the pixels that count.
  SELECT min(i.ord) INTO bad
  FROM json_array_elements(p_items::json) WITH ORDINALITY AS i(v, ord)
  JOIN json_array_elements(p_keys::json) WITH ORDINALITY AS k(v, ord) ON k.ord = i.ord
  WHERE i.v->>'kind' = 'locate' AND (coalesce(i.v->>'picture', '') = '' OR coalesce((i.v->>'picture_width')::integer, 0) <= 0
        OR coalesce((i.v->>'picture_height')::integer, 0) <= 0 OR json_typeof(k.v->'accepted_pixels') IS DISTINCT FROM 'array');
  IF bad IS NOT NULL THEN
    RAISE EXCEPTION 'item % locates a structure but comes without its picture, its size or the pixels that count', bad
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  INSERT INTO class_exams (class_code, exam_id, course_id, title, time_limit_s, pass_score, item_count, opened_by,
                           opened_at, prerequisites)
  VALUES (p_class, p_exam, p_course, coalesce(p_title, p_exam), p_limit, p_pass, n, actor, at_now(),
          coalesce(p_prerequisites, '[]')::json::text);
  INSERT INTO class_exam_items (class_code, exam_id, position, kind, prompt, choices, locate_view, scene, picture,
                                picture_width, picture_height)
  SELECT p_class, p_exam, (i.ord - 1)::integer, i.v->>'kind', coalesce(i.v->>'prompt', ''),
         coalesce((i.v->'choices')::text, '[]'), coalesce(i.v->>'locate_view', '3d'),
         coalesce((i.v->'scene')::text, '{}'), coalesce(i.v->>'picture', ''),
         coalesce((i.v->>'picture_width')::integer, 0), coalesce((i.v->>'picture_height')::integer, 0)
  FROM json_array_elements(p_items::json) WITH ORDINALITY AS i(v, ord);
  INSERT INTO class_exam_keys (class_code, exam_id, position, question_id, target, key_choice, names, tolerance_mm,
                               name_bodies, competitor_bodies, target_side, ask_side)
  SELECT p_class, p_exam, (k.ord - 1)::integer, coalesce(k.v->>'question_id', ''), k.v->>'target',
         coalesce((k.v->>'key_choice')::integer, -1), coalesce((k.v->'names')::text, '[]'),
         coalesce((k.v->>'tolerance_mm')::double precision, 0), coalesce((k.v->'name_bodies')::text, '[]'),
         coalesce((k.v->'competitor_bodies')::text, '[]'), coalesce(k.v->>'target_side', ''),
         coalesce((k.v->>'ask_side')::boolean, false)
  FROM json_array_elements(p_keys::json) WITH ORDINALITY AS k(v, ord);
  INSERT INTO class_exam_locate_keys (class_code, exam_id, position, y, x_from, x_to)
  SELECT p_class, p_exam, (k.ord - 1)::integer, (r.v->>0)::integer, (r.v->>1)::integer, (r.v->>2)::integer
  FROM json_array_elements(p_keys::json) WITH ORDINALITY AS k(v, ord)
  CROSS JOIN LATERAL json_array_elements(CASE WHEN json_typeof(k.v->'accepted_pixels') = 'array'
                                              THEN k.v->'accepted_pixels' ELSE '[]'::json END) AS r(v);
  PERFORM at_audit(actor, 'exam_open', p_class, p_exam, NULL, n || ' items', '');
  RETURN n;
END
$f$;

-- Starts the member's sitting (the clock runs from now) or returns the one started; its deadline.
-- A member who has not finished the exam's prerequisite lessons on the server is refused.
CREATE OR REPLACE FUNCTION at_start_exam(p_class text, p_exam text, p_by text) RETURNS bigint
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  x class_exams%ROWTYPE;
  s class_exam_sittings%ROWTYPE;
  missing text;
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
  SELECT string_agg(p.lesson, ', ' ORDER BY p.ord) INTO missing
  FROM json_array_elements_text(x.prerequisites::json) WITH ORDINALITY AS p(lesson, ord)
  WHERE NOT EXISTS (SELECT 1 FROM class_events e WHERE e.class_code = p_class AND e.user_name = actor
                    AND e.kind = 'lesson_finished' AND e.lesson_id = p.lesson);
  IF missing IS NOT NULL THEN
    RAISE EXCEPTION 'exam % is locked for % until % is finished (as the class server has it: sync first)', p_exam,
      actor, missing USING ERRCODE = 'insufficient_privilege';
  END IF;
  INSERT INTO class_exam_sittings (class_code, exam_id, user_name, started_at, deadline_at)
  VALUES (p_class, p_exam, actor, at_now(), at_now() + x.time_limit_s);
  RETURN at_now() + x.time_limit_s;
END
$f$;

-- Grades one answer on the server and keeps it; returns 'saved' (never the grade). Exactly the
-- member for the item's kind is given: p_choice (identify), p_text (name), p_x and p_y (locate: the
-- pixel clicked on the item's picture, 0-based from its top left).
CREATE FUNCTION at_answer_exam(p_class text, p_exam text, p_position integer, p_choice integer, p_text text,
                               p_x integer, p_y integer, p_latency bigint, p_by text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  s class_exam_sittings%ROWTYPE;
  i class_exam_items%ROWTYPE;
  k class_exam_keys%ROWTYPE;
  right_answer boolean;
  score double precision;
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
       OR p_x IS NOT NULL OR p_y IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for one of its % choices', p_position + 1, json_array_length(i.choices::json)
        USING ERRCODE = 'invalid_parameter_value';
    END IF;
    right_answer := p_choice = k.key_choice;
    given := json_build_object('choice', p_choice);
  ELSIF i.kind = 'name' THEN
    IF p_text IS NULL OR btrim(p_text) = '' OR p_choice IS NOT NULL OR p_x IS NOT NULL OR p_y IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for a name', p_position + 1 USING ERRCODE = 'invalid_parameter_value';
    END IF;
    IF k.name_bodies <> '[]' THEN
      score := at_grade_name(p_text, k.name_bodies, k.competitor_bodies, k.target_side, k.ask_side);
    ELSE  -- opened before the server had the laptop's rule: the names as they are
      score := CASE WHEN EXISTS (SELECT 1 FROM json_array_elements_text(k.names::json) AS n(name)
                                 WHERE at_exam_name(n.name) = at_exam_name(p_text)) THEN 1 ELSE 0 END;
    END IF;
    right_answer := score >= 1;
    given := json_build_object('text', p_text);
  ELSE
    IF p_x IS NULL OR p_y IS NULL OR p_choice IS NOT NULL OR p_text IS NOT NULL THEN
      RAISE EXCEPTION 'item % asks for the pixel clicked on its picture', p_position + 1
        USING ERRCODE = 'invalid_parameter_value';
    END IF;
    IF p_x < 0 OR p_y < 0 OR p_x >= i.picture_width OR p_y >= i.picture_height THEN
      RAISE EXCEPTION 'the pixel (%, %) is outside item %''s %×% picture', p_x, p_y, p_position + 1, i.picture_width,
        i.picture_height USING ERRCODE = 'invalid_parameter_value';
    END IF;
    right_answer := EXISTS (SELECT 1 FROM class_exam_locate_keys r WHERE r.class_code = p_class AND r.exam_id = p_exam
                            AND r.position = p_position AND r.y = p_y AND p_x BETWEEN r.x_from AND r.x_to);
    given := json_build_object('pixel', json_build_array(p_x, p_y));
  END IF;
  INSERT INTO class_exam_answers (class_code, exam_id, user_name, position, answer, correct, score, latency_ms, answered_at)
  VALUES (p_class, p_exam, actor, p_position, given::text, CASE WHEN right_answer THEN 1 ELSE 0 END,
          coalesce(score, CASE WHEN right_answer THEN 1 ELSE 0 END), greatest(coalesce(p_latency, 0), 0), at_now());
  RETURN 'saved';
END
$f$;

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  ALTER TABLE class_exam_locate_keys OWNER TO at_class_owner;
  EXECUTE format('REVOKE ALL ON %I.class_exam_locate_keys FROM PUBLIC', schema_name);
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_open_exam', 'at_start_exam', 'at_answer_exam',
             'at_fold_name', 'at_split_side', 'at_osa_distance', 'at_typo_allowance', 'at_grade_name') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef THEN EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn); END IF;
  END LOOP;
  -- The pixels that count are granted to no login: they are read only inside at_answer_exam.
END
$own$;
)SQL";
}

}  // namespace at::db
