// Lesson locate answers on the class server (after class_lesson_keys_sql.cpp):
//
//  - the laptop measures a click (the structure under it and its distance) from its own copy of
//    the dataset, so the server does not believe the pick a locate answer names. A locate key may
//    hold the question's fixed views (key "views": [{view, width, height, runs: [[y, x_from,
//    x_to], …]}]): the picture `play` shows for the question (its scene, framed as a locate
//    question), named by an id that changes with anything that moves a pick (camera, size, preset,
//    the dataset's voxels: TerminalViews::lastViewId), and the pixels whose click counts, worked
//    out on the instructor's machine by the laptop's own grader for every pixel.
//  - an answer picked on one of those views carries "pixel": [x, y] and "view": its id; the server
//    grades it from the runs alone (a pixel outside the picture is refused). Any other locate
//    answer — a click in the desktop's free 3-D view, a point in mm, a pick on a view the key
//    does not hold, a pick named without a pixel — is stored as ungraded practice: correct and
//    score blank, class_events.practice = 1, its payload saying so; `class progress` and analytics
//    leave it out of answers and right answers. A coordinator's audited correction still grades it.
//  - a lesson's end takes its score from the latest graded answer to each of its questions,
//    practice left out (blank while one waits for its key, or when every one is practice).
#include "class_lesson_locate_sql.h"

namespace at::db {

std::string_view classLessonLocateSqliteSql() {
  return "ALTER TABLE class_events ADD COLUMN practice INTEGER NOT NULL DEFAULT 0;\n";
}

std::string_view classLessonLocateSql() {
  return R"SQL(
ALTER TABLE class_events ADD COLUMN practice bigint NOT NULL DEFAULT 0;

-- The grade (0 or 1) of a locate answer picked on one of the key's views, NULL when it was not
-- picked on one (practice); raises invalid_parameter_value for a malformed or outside pixel.
CREATE FUNCTION at_locate_pixel_grade(p_key jsonb, p_answer jsonb) RETURNS double precision
LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  q text := p_key->>'question_id';
  v jsonb;
  x integer;
  y integer;
BEGIN
  IF jsonb_typeof(p_answer) IS DISTINCT FROM 'object' OR NOT (p_answer ? 'pixel' OR p_answer ? 'view') THEN
    RETURN NULL;
  END IF;
  IF jsonb_typeof(p_answer->'view') IS DISTINCT FROM 'string' OR jsonb_typeof(p_answer->'pixel') IS DISTINCT FROM 'array'
     OR jsonb_array_length(p_answer->'pixel') <> 2
     OR EXISTS (SELECT 1 FROM jsonb_array_elements(p_answer->'pixel') e
                WHERE jsonb_typeof(e) <> 'number' OR e::text !~ '^-?[0-9]{1,9}$') THEN
    RAISE EXCEPTION 'question % (locate): a pick on a picture is "pixel": [x, y] in whole pixels with the "view" it was made on', q
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  x := (p_answer->'pixel'->>0)::integer;
  y := (p_answer->'pixel'->>1)::integer;
  SELECT e INTO v FROM jsonb_array_elements(coalesce(p_key->'views', '[]'::jsonb)) e
  WHERE e->>'view' = p_answer->>'view' LIMIT 1;
  IF v IS NULL THEN RETURN NULL; END IF;
  IF x < 0 OR y < 0 OR x >= (v->>'width')::integer OR y >= (v->>'height')::integer THEN
    RAISE EXCEPTION 'question %: the pixel (%, %) is outside the %×% picture', q, x, y, v->>'width', v->>'height'
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  RETURN CASE WHEN EXISTS (SELECT 1 FROM jsonb_array_elements(v->'runs') r
                           WHERE (r->>0)::integer = y AND x BETWEEN (r->>1)::integer AND (r->>2)::integer) THEN 1 ELSE 0 END;
END
$f$;

-- at_grade_lesson_answer as migration 22 made it, kept for every kind but locate (and for the form
-- of a locate answer). The name at_grade_lesson_answer, which at_record_event and
-- at_publish_lesson_keys call, now grades locate answers from their pixels (NULL: practice).
ALTER FUNCTION at_grade_lesson_answer(jsonb, jsonb) RENAME TO at_grade_lesson_answer_as_sent;
CREATE FUNCTION at_grade_lesson_answer(p_key jsonb, p_answer jsonb) RETURNS double precision
LANGUAGE plpgsql IMMUTABLE AS $f$
BEGIN
  IF p_key->>'kind' = 'locate' THEN
    PERFORM at_grade_lesson_answer_as_sent(p_key, p_answer);  -- raises for an answer of the wrong form
    RETURN at_locate_pixel_grade(p_key, p_answer);
  END IF;
  RETURN at_grade_lesson_answer_as_sent(p_key, p_answer);
END
$f$;

-- Every answer stored or re-graded: an answer left without a score to a locate question whose key
-- is published is practice (correct blank, practice = 1, the payload saying why); a lesson's end
-- is scored from the latest graded answers, practice left out.
CREATE FUNCTION at_class_event_practice() RETURNS trigger LANGUAGE plpgsql AS $f$
DECLARE
  payload jsonb;
  waiting boolean;
BEGIN
  BEGIN
    payload := NEW.payload::jsonb;
  EXCEPTION WHEN others THEN
    payload := NULL;
  END;
  IF jsonb_typeof(payload) IS DISTINCT FROM 'object' THEN payload := '{}'::jsonb; END IF;
  IF NEW.kind = 'answer' THEN
    IF NEW.score IS NOT NULL THEN
      NEW.practice := 0;  -- graded (by the server, or a coordinator's correction)
    ELSIF EXISTS (SELECT 1 FROM questions WHERE id = NEW.question_id AND kind = 'locate')
       AND EXISTS (SELECT 1 FROM class_lesson_keys WHERE class_code = NEW.class_code AND question_id = NEW.question_id) THEN
      NEW.correct := NULL;
      NEW.practice := 1;
      NEW.payload := (payload - 'correct' - 'score' - 'fsrs_rating' || jsonb_build_object('graded', false, 'practice',
        'a locate answer counts only when picked on the question''s picture (anatomy-tutor play); this one is practice'))::text;
    END IF;
  ELSIF NEW.kind = 'lesson_finished' AND TG_OP = 'INSERT' THEN
    SELECT CASE WHEN count(*) = 0 THEN 1.0
                WHEN bool_or(latest.score IS NULL AND latest.practice = 0) THEN NULL
                ELSE avg(latest.score) FILTER (WHERE latest.practice = 0) END,
           bool_or(latest.score IS NULL AND latest.practice = 0)
    INTO NEW.score, waiting
    FROM steps s CROSS JOIN LATERAL (
      SELECT e.score, e.practice FROM class_events e
      WHERE e.class_code = NEW.class_code AND e.user_name = NEW.user_name AND e.kind = 'answer'
        AND e.lesson_id = NEW.lesson_id AND e.question_id = s.question_id
      ORDER BY e.practice, e.occurred_at DESC, e.received_at DESC LIMIT 1
    ) latest
    WHERE s.lesson_id = NEW.lesson_id AND s.kind = 'question';
    NEW.payload := (payload || jsonb_build_object('score', NEW.score))::text;
  END IF;
  RETURN NEW;
END
$f$;
CREATE TRIGGER class_events_practice BEFORE INSERT OR UPDATE ON class_events
  FOR EACH ROW WHEN (NEW.kind IN ('answer', 'lesson_finished')) EXECUTE FUNCTION at_class_event_practice();

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_locate_pixel_grade', 'at_grade_lesson_answer',
             'at_grade_lesson_answer_as_sent', 'at_class_event_practice') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
  END LOOP;
END
$own$;
)SQL";
}

}  // namespace at::db
