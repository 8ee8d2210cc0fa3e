// Lesson answers graded on the class server, PostgreSQL only (a SQLite file is one person's laptop):
//
//  - the class's instructor or coordinator publishes the keys of a course's questions
//    (at_publish_lesson_keys), resolved on their machine from the course's dataset by the laptop's
//    own key computation (quiz::resolveQuestion): the target, the offered choices and the key
//    choice, the structures a drilling path meets, the accepted spellings. They go into
//    class_lesson_keys, which no login can read. Publishing is audited (lesson_keys) and re-grades
//    the class's answers to those questions from the answers they carry.
//  - at_record_event grades every lesson or review answer from its key and the answer the event
//    carries (payload "answer"): the `correct` and `score` the laptop sends are not believed. The
//    stored event, its payload's grade and FSRS rating are the server's. An answer that does not
//    fit its question (a choice out of range, the wrong form) is refused with the reason. An answer
//    to a question without a published key is kept ungraded (correct and score blank) until its
//    key is published. A lesson's end takes its score from the server's grades of that lesson.
//
// Grading follows quiz::grade (quiz/grading.h) exactly: locate by the structure under the click or
// the distance within the tolerance (both measured on the student's machine: the server has no
// volume), identify and relation by the key choice, name by at_grade_name (class_exam_locate_sql),
// order by LCS(answer, key) / max(lengths) with entries resolved as quiz's resolveStructure does.
#include "class_lesson_keys_sql.h"

namespace at::db {

std::string_view classLessonKeysSql() {
  return R"SQL(
CREATE TABLE class_lesson_keys (
  class_code    text NOT NULL REFERENCES classes(code) ON DELETE CASCADE,
  question_id   text NOT NULL,
  key           jsonb NOT NULL,
  published_by  text NOT NULL,
  published_at  bigint NOT NULL,
  PRIMARY KEY (class_code, question_id)
);
ALTER TABLE class_lesson_keys ENABLE ROW LEVEL SECURITY;

-- quiz::normalizeName: the folded words without articles, the side words (as left / right) last.
CREATE FUNCTION at_normalize_name(p text) RETURNS text LANGUAGE sql IMMUTABLE AS $f$
  SELECT coalesce(string_agg(CASE WHEN w IN ('l', 'left') THEN 'left' WHEN w IN ('r', 'right') THEN 'right' ELSE w END,
                             ' ' ORDER BY (w IN ('l', 'left', 'r', 'right')), n), '')
  FROM regexp_split_to_table(btrim(at_fold_name(p)), '\s+') WITH ORDINALITY AS t(w, n)
  WHERE w <> '' AND w NOT IN ('the', 'a', 'an')
$f$;

-- quiz::longestCommonSubsequence of two text arrays.
CREATE FUNCTION at_lcs_length(a text[], b text[]) RETURNS integer LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  n integer := coalesce(array_length(a, 1), 0);
  m integer := coalesce(array_length(b, 1), 0);
  t integer[];
  w integer := m + 1;
BEGIN
  IF n = 0 OR m = 0 THEN RETURN 0; END IF;
  t := array_fill(0, ARRAY[(n + 1) * w]);
  FOR i IN 1..n LOOP
    FOR j IN 1..m LOOP
      t[i * w + j + 1] := CASE WHEN a[i] = b[j] THEN t[(i - 1) * w + j] + 1
                               ELSE greatest(t[(i - 1) * w + j + 1], t[i * w + j]) END;
    END LOOP;
  END LOOP;
  RETURN t[n * w + m + 1];
END
$f$;

-- Why `p_answer` (the laptop's answer JSON) cannot answer a question of kind `p_kind`, or NULL when
-- it has the form quiz::grade takes: exactly one of choice (identify, relation: an index), text
-- (name), pick (locate: a structure id or null, distance_mm a number >= 0 when given) or order (an
-- array of strings).
CREATE FUNCTION at_answer_misfit(p_kind text, p_answer jsonb) RETURNS text LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE
    WHEN jsonb_typeof(p_answer) IS DISTINCT FROM 'object' THEN 'it carries no answer'
    WHEN (SELECT count(*) FROM jsonb_object_keys(p_answer) k WHERE k IN ('choice', 'text', 'pick', 'order')) <> 1
      THEN 'an answer needs exactly one of choice, text, pick or order'
    WHEN p_kind = 'locate' AND NOT (jsonb_typeof(p_answer->'pick') IN ('string', 'null')
                                    AND coalesce(jsonb_typeof(p_answer->'distance_mm'), 'number') = 'number'
                                    AND coalesce(CASE WHEN jsonb_typeof(p_answer->'distance_mm') = 'number'
                                                      THEN (p_answer->>'distance_mm')::double precision END, 0) >= 0)
      THEN 'a locate question needs a pick (a structure id, and its distance_mm >= 0)'
    WHEN p_kind IN ('identify', 'relation') AND NOT (jsonb_typeof(p_answer->'choice') = 'number'
                                                     AND (p_answer->>'choice') ~ '^[0-9]{1,9}$')
      THEN 'an ' || p_kind || ' question needs a choice (an index)'
    WHEN p_kind = 'name' AND jsonb_typeof(p_answer->'text') IS DISTINCT FROM 'string'
      THEN 'a name question needs a typed name'
    WHEN p_kind = 'order' AND (jsonb_typeof(p_answer->'order') IS DISTINCT FROM 'array'
                               OR EXISTS (SELECT 1 FROM jsonb_array_elements(p_answer->'order') e WHERE jsonb_typeof(e) <> 'string'))
      THEN 'an order question needs an order of structures'
  END
$f$;

-- The score (0..1) of `p_answer` (the laptop's answer JSON) against `p_key`; raises
-- invalid_parameter_value, saying why, for an answer that does not fit the question.
CREATE FUNCTION at_grade_lesson_answer(p_key jsonb, p_answer jsonb) RETURNS double precision
LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  kind text := p_key->>'kind';
  q text := p_key->>'question_id';
  fields integer;
  choice integer;
  n integer;
  distance double precision;
  ids text[] := '{}';
  entry text;
  id text;
  key_order text[];
  common integer;
BEGIN
  IF jsonb_typeof(p_answer) IS DISTINCT FROM 'object' THEN
    RAISE EXCEPTION 'question % came without its answer', q USING ERRCODE = 'invalid_parameter_value';
  END IF;
  SELECT count(*) INTO fields FROM jsonb_object_keys(p_answer) k WHERE k IN ('choice', 'text', 'pick', 'order');
  IF fields <> 1 THEN
    RAISE EXCEPTION 'question %: an answer needs exactly one of choice, text, pick or order', q
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF kind = 'locate' THEN
    IF NOT p_answer ? 'pick' OR jsonb_typeof(p_answer->'pick') NOT IN ('string', 'null') THEN
      RAISE EXCEPTION 'question % (locate) needs a pick', q USING ERRCODE = 'invalid_parameter_value';
    END IF;
    IF p_answer->>'pick' IS NOT DISTINCT FROM p_key->>'target' THEN RETURN 1; END IF;
    IF jsonb_typeof(p_answer->'distance_mm') = 'number' THEN distance := (p_answer->>'distance_mm')::double precision; END IF;
    IF (p_key->>'tolerance_mm')::double precision > 0 AND distance IS NOT NULL AND distance >= 0
       AND distance <= (p_key->>'tolerance_mm')::double precision + 1e-6 THEN
      RETURN 1;
    END IF;
    RETURN 0;
  ELSIF kind IN ('identify', 'relation') THEN
    n := jsonb_array_length(p_key->'choices');
    IF jsonb_typeof(p_answer->'choice') IS DISTINCT FROM 'number' OR (p_answer->>'choice') !~ '^-?[0-9]{1,9}$' THEN
      RAISE EXCEPTION 'question % (%) needs a choice', q, kind USING ERRCODE = 'invalid_parameter_value';
    END IF;
    choice := (p_answer->>'choice')::integer;
    IF choice < 0 OR choice >= n THEN
      RAISE EXCEPTION 'question %: choice % is out of range 0..%', q, choice, n - 1 USING ERRCODE = 'invalid_parameter_value';
    END IF;
    RETURN CASE WHEN choice = (p_key->>'key_choice')::integer THEN 1 ELSE 0 END;
  ELSIF kind = 'name' THEN
    IF jsonb_typeof(p_answer->'text') IS DISTINCT FROM 'string' THEN
      RAISE EXCEPTION 'question % (name) needs a typed name', q USING ERRCODE = 'invalid_parameter_value';
    END IF;
    RETURN at_grade_name(p_answer->>'text', (p_key->'name_bodies')::text, (p_key->'competitor_bodies')::text,
                         p_key->>'target_side', coalesce((p_key->>'ask_side')::boolean, false));
  ELSIF kind = 'order' THEN
    IF jsonb_typeof(p_answer->'order') IS DISTINCT FROM 'array'
       OR EXISTS (SELECT 1 FROM jsonb_array_elements(p_answer->'order') e WHERE jsonb_typeof(e) <> 'string') THEN
      RAISE EXCEPTION 'question % (order) needs an order of structures', q USING ERRCODE = 'invalid_parameter_value';
    END IF;
    FOR entry IN SELECT e FROM jsonb_array_elements_text(p_answer->'order') WITH ORDINALITY AS t(e, i) ORDER BY i LOOP
      IF (p_key->'structure_ids') ? entry THEN
        id := entry;
      ELSE
        SELECT s.v->>1 INTO id FROM jsonb_array_elements(p_key->'spellings') WITH ORDINALITY AS s(v, i)
        WHERE s.v->>0 = at_normalize_name(entry) ORDER BY s.i LIMIT 1;
        IF id IS NULL THEN
          RAISE EXCEPTION 'question %: order: unknown structure ''%''', q, entry USING ERRCODE = 'invalid_parameter_value';
        END IF;
      END IF;
      ids := ids || id;
      id := NULL;
    END LOOP;
    SELECT array_agg(e ORDER BY i) INTO key_order FROM jsonb_array_elements_text(p_key->'key_order') WITH ORDINALITY AS t(e, i);
    IF ids = key_order THEN RETURN 1; END IF;
    common := at_lcs_length(ids, key_order);
    RETURN common::double precision / greatest(coalesce(array_length(ids, 1), 0), coalesce(array_length(key_order, 1), 0));
  END IF;
  RAISE EXCEPTION 'question % has a key of unknown kind %', q, coalesce(kind, 'NULL') USING ERRCODE = 'invalid_parameter_value';
END
$f$;

-- The payload of an answer event with the server's grade in place of the laptop's: its correct and
-- score, and an FSRS rating that agrees with them (lessons/scheduling.cpp ratingFor: wrong → Hard
-- for a score of at least 0.5, else Again; right → the laptop's Good or Easy, at least Good).
CREATE FUNCTION at_graded_payload(p_payload jsonb, p_correct integer, p_score double precision) RETURNS jsonb
LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE WHEN p_correct IS NULL THEN p_payload - 'correct' - 'score' - 'fsrs_rating' || '{"graded": false}'::jsonb
              ELSE p_payload || jsonb_build_object('correct', p_correct = 1, 'score', p_score, 'fsrs_rating',
                     CASE WHEN p_correct = 0 THEN CASE WHEN p_score >= 0.5 THEN 2 ELSE 1 END
                          ELSE greatest(3, least(4, coalesce((p_payload->>'fsrs_rating')::integer, 3))) END) END
$f$;

-- An instructor or coordinator of the class publishes (or replaces) the keys of questions on the
-- server: p_keys is a JSON array of {question_id, kind, target, choices, key_choice, key_order,
-- tolerance_mm, name_bodies, competitor_bodies, target_side, ask_side, structure_ids, spellings}.
-- Each question must be on the server with that kind and target. The class's answers to those
-- questions are graded from their answers (see below). Returns the number of keys.
CREATE FUNCTION at_publish_lesson_keys(p_class text, p_keys text, p_by text) RETURNS integer
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  r text;
  keys jsonb;
  k jsonb;
  q questions%ROWTYPE;
  e record;
  old_key jsonb;
  given jsonb;
  s double precision;
  n integer := 0;
BEGIN
  IF NOT EXISTS (SELECT 1 FROM classes WHERE code = p_class) THEN
    RAISE EXCEPTION 'no class has the code %', p_class USING ERRCODE = 'no_data_found';
  END IF;
  IF at_is_account() OR coalesce(p_by, '') <> '' THEN
    SELECT role INTO r FROM class_members WHERE class_code = p_class AND user_name = actor AND withdrawn_at IS NULL;
    IF r IS NULL OR r NOT IN ('instructor', 'coordinator') THEN
      RAISE EXCEPTION '''%'' is % of class %; only its instructors and coordinators publish answer keys', actor,
        coalesce(r, 'not a member'), p_class USING ERRCODE = 'insufficient_privilege';
    END IF;
  END IF;
  BEGIN
    keys := p_keys::jsonb;
  EXCEPTION WHEN others THEN
    keys := NULL;
  END;
  IF jsonb_typeof(keys) IS DISTINCT FROM 'array' THEN
    RAISE EXCEPTION 'the answer keys must be a JSON array' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  FOR k IN SELECT v FROM jsonb_array_elements(keys) AS t(v) LOOP
    SELECT * INTO q FROM questions WHERE id = k->>'question_id';
    IF NOT FOUND THEN
      RAISE EXCEPTION 'there is no question % on the class server (seed its course there first)',
        coalesce(k->>'question_id', 'NULL') USING ERRCODE = 'invalid_parameter_value';
    END IF;
    IF k->>'kind' IS DISTINCT FROM q.kind OR k->>'target' IS DISTINCT FROM q.target THEN
      RAISE EXCEPTION 'the key of question % is for a % question on %, but the server has a % question on %', q.id,
        coalesce(k->>'kind', 'NULL'), coalesce(k->>'target', 'NULL'), q.kind, q.target USING ERRCODE = 'invalid_parameter_value';
    END IF;
    IF q.kind IN ('identify', 'relation') AND (jsonb_typeof(k->'choices') IS DISTINCT FROM 'array'
         OR (k->>'key_choice')::integer NOT BETWEEN 0 AND jsonb_array_length(k->'choices') - 1)
       OR q.kind = 'order' AND (jsonb_typeof(k->'key_order') IS DISTINCT FROM 'array' OR jsonb_array_length(k->'key_order') = 0)
       OR q.kind = 'name' AND jsonb_typeof(k->'name_bodies') IS DISTINCT FROM 'array' THEN
      RAISE EXCEPTION 'the key of question % lacks its choices and key choice, its order or its names', q.id
        USING ERRCODE = 'invalid_parameter_value';
    END IF;
    SELECT key INTO old_key FROM class_lesson_keys WHERE class_code = p_class AND question_id = q.id;
    INSERT INTO class_lesson_keys (class_code, question_id, key, published_by, published_at)
    VALUES (p_class, q.id, k, actor, at_now())
    ON CONFLICT (class_code, question_id) DO UPDATE SET key = excluded.key, published_by = excluded.published_by,
      published_at = excluded.published_at;
    -- Graded again: the answers waiting ungraded, and when the key changed the others — except an
    -- answer a coordinator corrected (at_correct_event, audited), whose correction stands.
    FOR e IN SELECT ev.uuid, ev.payload FROM class_events ev
             WHERE ev.class_code = p_class AND ev.kind = 'answer' AND ev.question_id = q.id
               AND (ev.correct IS NULL OR old_key IS DISTINCT FROM k)
               AND NOT EXISTS (SELECT 1 FROM class_audit a WHERE a.action = 'correct' AND a.class_code = p_class
                               AND a.target = ev.user_name || ' ' || ev.uuid) LOOP
      BEGIN
        given := e.payload::jsonb;
      EXCEPTION WHEN others THEN
        given := '{}'::jsonb;
      END;
      IF jsonb_typeof(given) IS DISTINCT FROM 'object' THEN given := '{}'::jsonb; END IF;
      BEGIN
        s := at_grade_lesson_answer(k, given->'answer');
      EXCEPTION WHEN invalid_parameter_value THEN
        s := 0;  -- stored before its key: an answer that does not fit it counts as wrong
      END;
      UPDATE class_events SET correct = CASE WHEN s >= 1 THEN 1 ELSE 0 END, score = s,
        payload = at_graded_payload(given, CASE WHEN s >= 1 THEN 1 ELSE 0 END, s)::text
      WHERE uuid = e.uuid;
    END LOOP;
    n := n + 1;
  END LOOP;
  PERFORM at_audit(actor, 'lesson_keys', p_class, n || ' questions', NULL, md5(p_keys), '');
  RETURN n;
END
$f$;

-- One outbox event: 'stored', 'repeated' (this sender sent it before) or 'refused: <why>'. The
-- checks of class_security_sql.cpp, and an answer graded here (see above).
CREATE OR REPLACE FUNCTION at_record_event(p_uuid text, p_class text, p_user text, p_kind text, p_occurred bigint,
                                           p_lesson text, p_question text, p_structure text, p_correct bigint,
                                           p_score double precision, p_payload text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  sender text := session_user;
  q questions%ROWTYPE;
  lesson text := coalesce(p_lesson, '');
  lesson_of_answer text := coalesce(p_lesson, '');
  missing text;
  earlier text;
  payload jsonb;
  k jsonb;
  graded_correct integer;
  graded_score double precision;
  structure text := coalesce(p_structure, '');
BEGIN
  IF at_is_account() THEN
    IF p_user IS DISTINCT FROM sender THEN
      RETURN format('refused: event %s names %s but was sent by the login %s', p_uuid, coalesce(p_user, 'nobody'), sender);
    END IF;
  ELSE
    sender := p_user;
  END IF;
  IF p_uuid IS NULL OR p_uuid !~ '^[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}$' THEN
    RETURN format('refused: event id %s is not a UUID', coalesce(p_uuid, 'NULL'));
  END IF;
  SELECT user_name INTO earlier FROM class_events WHERE uuid = p_uuid;
  IF FOUND THEN
    IF earlier = sender THEN RETURN 'repeated'; END IF;
    RETURN format('refused: event id %s is already used', p_uuid);
  END IF;
  IF NOT EXISTS (SELECT 1 FROM class_members WHERE class_code = p_class AND user_name = sender AND withdrawn_at IS NULL) THEN
    RETURN format('refused: %s is not a current member of class %s', sender, p_class);
  END IF;
  IF p_kind IS NULL OR p_kind NOT IN ('answer', 'lesson_started', 'lesson_finished') THEN
    RETURN format('refused: event kind %s is not answer, lesson_started or lesson_finished', coalesce(p_kind, 'NULL'));
  END IF;
  IF p_occurred IS NULL OR p_occurred > extract(epoch FROM now())::bigint + 86400 OR p_occurred < 946684800 THEN
    RETURN format('refused: event %s happened at an impossible time (%s)', p_uuid, coalesce(p_occurred::text, 'NULL'));
  END IF;
  BEGIN
    payload := coalesce(p_payload, '{}')::jsonb;
  EXCEPTION WHEN others THEN
    payload := NULL;
  END;
  IF jsonb_typeof(payload) IS DISTINCT FROM 'object' THEN
    RETURN format('refused: event %s carries no JSON object', p_uuid);
  END IF;
  IF p_kind = 'answer' THEN
    SELECT * INTO q FROM questions WHERE id = p_question;
    IF NOT FOUND THEN
      RETURN format('refused: there is no question %s on the class server', coalesce(p_question, 'NULL'));
    END IF;
    IF lesson <> '' AND lesson <> q.lesson_id THEN
      RETURN format('refused: question %s is not in lesson %s', p_question, lesson);
    END IF;
    lesson := q.lesson_id;  -- a review answer counts only for a lesson the person may take
    structure := q.target;  -- the question's structure, whatever the laptop named
  ELSIF NOT EXISTS (SELECT 1 FROM lessons WHERE id = lesson) THEN
    RETURN format('refused: there is no lesson %s on the class server', lesson);
  END IF;
  SELECT string_agg(pr.requires_id, ', ' ORDER BY pr.position) INTO missing
  FROM lesson_prerequisites pr
  WHERE pr.lesson_id = lesson AND NOT EXISTS (
    SELECT 1 FROM class_events e WHERE e.class_code = p_class AND e.user_name = sender
      AND e.kind = 'lesson_finished' AND e.lesson_id = pr.requires_id);
  IF missing IS NOT NULL THEN
    RETURN format('refused: lesson %s is locked for %s until %s is finished', lesson, sender, missing);
  END IF;
  -- A review answer (no lesson) needs its lesson unlocked, not an attempt at it.
  IF p_kind <> 'lesson_started' AND lesson_of_answer <> '' AND NOT EXISTS (
      SELECT 1 FROM class_events e WHERE e.class_code = p_class AND e.user_name = sender
        AND e.kind = 'lesson_started' AND e.lesson_id = lesson) THEN
    RETURN format('refused: %s never started lesson %s', sender, lesson);
  END IF;
  IF p_kind = 'answer' THEN
    missing := at_answer_misfit(q.kind, payload->'answer');
    IF missing IS NOT NULL THEN
      RETURN format('refused: answer %s to question %s: %s', p_uuid, q.id, missing);
    END IF;
    IF p_correct IS NULL OR p_correct NOT IN (0, 1) OR p_score IS NULL OR p_score < 0 OR p_score > 1 THEN
      RETURN format('refused: answer %s has an impossible grade', p_uuid);  -- a laptop never sends one
    END IF;
    SELECT key INTO k FROM class_lesson_keys WHERE class_code = p_class AND question_id = q.id;
    IF FOUND THEN
      BEGIN
        graded_score := at_grade_lesson_answer(k, payload->'answer');
      EXCEPTION WHEN invalid_parameter_value THEN
        RETURN format('refused: answer %s: %s', p_uuid, SQLERRM);
      END;
      graded_correct := CASE WHEN graded_score >= 1 THEN 1 ELSE 0 END;
    END IF;  -- no key yet: kept ungraded until at_publish_lesson_keys grades it
    payload := at_graded_payload(payload, graded_correct, graded_score);
  ELSIF p_kind = 'lesson_finished' THEN
    SELECT string_agg(s.question_id, ', ' ORDER BY s.position) INTO missing
    FROM steps s
    WHERE s.lesson_id = lesson AND s.kind = 'question' AND NOT EXISTS (
      SELECT 1 FROM class_events e WHERE e.class_code = p_class AND e.user_name = sender AND e.kind = 'answer'
        AND e.lesson_id = lesson AND e.question_id = s.question_id);
    IF missing IS NOT NULL THEN
      RETURN format('refused: %s finished lesson %s without answering %s', sender, lesson, missing);
    END IF;
    -- The lesson's score: the mean of the server's grades of its questions' latest answers (blank
    -- while one of them is ungraded).
    SELECT CASE WHEN count(*) = 0 THEN 1.0 WHEN bool_and(latest.score IS NOT NULL) THEN avg(latest.score) END
    INTO graded_score
    FROM steps s CROSS JOIN LATERAL (
      SELECT e.score FROM class_events e WHERE e.class_code = p_class AND e.user_name = sender AND e.kind = 'answer'
        AND e.lesson_id = lesson AND e.question_id = s.question_id ORDER BY e.occurred_at DESC, e.received_at DESC LIMIT 1
    ) latest
    WHERE s.lesson_id = lesson AND s.kind = 'question';
    payload := payload || jsonb_build_object('score', graded_score);
  END IF;
  INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,
                            correct, score, payload, received_at)
  VALUES (p_uuid, p_class, sender, p_kind, p_occurred, coalesce(p_lesson, ''), coalesce(p_question, ''),
          structure, graded_correct, graded_score, payload::text, extract(epoch FROM now())::bigint);
  RETURN 'stored';
END
$f$;

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  ALTER TABLE class_lesson_keys OWNER TO at_class_owner;
  EXECUTE format('REVOKE ALL ON %I.class_lesson_keys FROM PUBLIC', schema_name);
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_normalize_name', 'at_lcs_length', 'at_answer_misfit', 'at_grade_lesson_answer',
             'at_graded_payload', 'at_publish_lesson_keys', 'at_record_event') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef THEN EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn); END IF;
  END LOOP;
  -- The keys are granted to no login: they are read only inside at_record_event.
END
$own$;
)SQL";
}

}  // namespace at::db
