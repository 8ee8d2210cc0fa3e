// A lesson's end scored again when its answers are graded again, PostgreSQL only (after
// class_lesson_locate_sql.cpp):
//
//  - a lesson_finished event takes its score, when it is stored, from the latest graded answer to
//    each of its lesson's questions (practice left out; blank while one waits for its key). Until
//    now that score stayed as stored: an end sent before the keys were published stayed blank, and
//    one whose answers a coordinator corrected kept the old mean.
//  - at_lesson_end_score is that score for one end, counting only the answers given up to the end
//    (an earlier end of the same lesson is not scored from a later run's answers). A stored end now
//    takes it too.
//  - whenever an answer's grade or practice flag changes (at_publish_lesson_keys grading answers
//    that waited or following a changed key, at_correct_event's correction — both audited), every
//    end of that lesson by that student at or after the answer is scored again when that
//    transaction commits, and each end whose score changes is recorded in class_audit (action
//    'lesson_score': who, old, new, which answer), after the act's own audit row — so no end
//    score changes without a trace. The ends stored before this migration are scored once the same
//    way when it runs.
#include "class_lesson_end_sql.h"

namespace at::db {

std::string_view classLessonEndSql() {
  return R"SQL(
-- The score of a lesson end: the mean of the latest graded answer to each question of the lesson
-- given by p_until (practice left out); 1 when none was answered; NULL while one of them waits for
-- its key, or when every one is practice.
CREATE FUNCTION at_lesson_end_score(p_class text, p_user text, p_lesson text, p_until bigint) RETURNS double precision
LANGUAGE sql STABLE AS $f$
  SELECT CASE WHEN count(*) = 0 THEN 1.0
              WHEN bool_or(latest.score IS NULL AND latest.practice = 0) THEN NULL
              ELSE avg(latest.score) FILTER (WHERE latest.practice = 0) END
  FROM steps s CROSS JOIN LATERAL (
    SELECT e.score, e.practice FROM class_events e
    WHERE e.class_code = p_class AND e.user_name = p_user AND e.kind = 'answer'
      AND e.lesson_id = p_lesson AND e.question_id = s.question_id AND e.occurred_at <= p_until
    ORDER BY e.practice, e.occurred_at DESC, e.received_at DESC LIMIT 1
  ) latest
  WHERE s.lesson_id = p_lesson AND s.kind = 'question'
$f$;

-- As migration 25 made it, but a lesson end is scored by at_lesson_end_score (up to its own time).
CREATE OR REPLACE FUNCTION at_class_event_practice() RETURNS trigger LANGUAGE plpgsql AS $f$
DECLARE
  payload jsonb;
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
    NEW.score := at_lesson_end_score(NEW.class_code, NEW.user_name, NEW.lesson_id, NEW.occurred_at);
    NEW.payload := (payload || jsonb_build_object('score', NEW.score))::text;
  END IF;
  RETURN NEW;
END
$f$;

-- After an answer's grade changed: its lesson's ends from then on, scored again and audited. It
-- runs at commit, outside the SECURITY DEFINER function that changed the grade, so it is one itself
-- (a trigger function cannot be called but by its trigger, which only those functions set off).
CREATE FUNCTION at_rescore_lesson_ends() RETURNS trigger LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  f record;
  s double precision;
BEGIN
  FOR f IN SELECT uuid, user_name, class_code, lesson_id, occurred_at, score, payload FROM class_events
           WHERE class_code = NEW.class_code AND user_name = NEW.user_name AND kind = 'lesson_finished'
             AND lesson_id = NEW.lesson_id AND occurred_at >= NEW.occurred_at
           FOR UPDATE LOOP
    s := at_lesson_end_score(f.class_code, f.user_name, f.lesson_id, f.occurred_at);
    CONTINUE WHEN s IS NOT DISTINCT FROM f.score;
    UPDATE class_events SET score = s, payload = (payload::jsonb || jsonb_build_object('score', s))::text
    WHERE uuid = f.uuid;
    PERFORM at_audit(session_user, 'lesson_score', f.class_code, f.user_name || ' ' || f.uuid,
                     json_build_object('score', f.score)::text, json_build_object('score', s)::text,
                     'the answer ' || NEW.uuid || ' to ' || NEW.question_id || ' was graded again');
  END LOOP;
  RETURN NULL;
END
$f$;
-- Deferred to the end of the transaction: an end is scored once from all the grades its
-- transaction changed (one audit row for it, after the row of the act that caused it).
CREATE CONSTRAINT TRIGGER class_events_rescore_lesson_ends AFTER UPDATE ON class_events
  DEFERRABLE INITIALLY DEFERRED FOR EACH ROW WHEN (NEW.kind = 'answer' AND (OLD.score IS DISTINCT FROM NEW.score OR OLD.practice IS DISTINCT FROM NEW.practice))
  EXECUTE FUNCTION at_rescore_lesson_ends();

-- The ends stored before: scored once by that rule, each change audited.
DO $rescore$
DECLARE
  f record;
  s double precision;
BEGIN
  FOR f IN SELECT uuid, user_name, class_code, lesson_id, occurred_at, score FROM class_events
           WHERE kind = 'lesson_finished' LOOP
    s := at_lesson_end_score(f.class_code, f.user_name, f.lesson_id, f.occurred_at);
    CONTINUE WHEN s IS NOT DISTINCT FROM f.score;
    BEGIN
      UPDATE class_events SET score = s, payload = (payload::jsonb || jsonb_build_object('score', s))::text WHERE uuid = f.uuid;
    EXCEPTION WHEN invalid_text_representation THEN
      UPDATE class_events SET score = s WHERE uuid = f.uuid;  -- a payload that is not JSON stays as it was
    END;
    PERFORM at_audit(session_user, 'lesson_score', f.class_code, f.user_name || ' ' || f.uuid,
                     json_build_object('score', f.score)::text, json_build_object('score', s)::text,
                     'scored again from its graded answers when the server began re-scoring lesson ends');
  END LOOP;
END
$rescore$;

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_lesson_end_score', 'at_class_event_practice',
             'at_rescore_lesson_ends') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
  END LOOP;
END
$own$;
)SQL";
}

}  // namespace at::db
