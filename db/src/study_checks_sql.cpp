// What a study's writes are checked against on a class server, PostgreSQL only (after
// study_writes_sql.cpp):
//
//  - every write to a study (registering, handing over, drawing a row, enrolling, ratings, viewing
//    times, completing, withdrawing and excluding) needs a login that is a class's coordinator now:
//    a coordinator demoted (or withdrawn) in every class writes nothing more, not even to the
//    studies she owns. The administrator (no class login) is not checked.
//  - a new participant's trials must be the row of the counterbalancing design the server drew for
//    them (quiz::planParticipant: the seeded permutation of the structures, the Williams square's
//    row, which condition is A), and a row goes to one participant only. at_study_plan computes the
//    row here, with quiz's own splitmix64 in unsigned 64-bit arithmetic.
//  - `study merge` into a server writes each participant it adds through at_merge_participant:
//    the study's current coordinator only, checked against the study's design, audited.
#include "study_checks_sql.h"

namespace at::db {

std::string_view studyChecksSql() {
  return R"SQL(
-- Raises unless this connection is the administrator or a login that coordinates a class now.
CREATE FUNCTION at_require_current_coordinator() RETURNS void LANGUAGE plpgsql STABLE AS $f$
BEGIN
  IF at_is_account() AND NOT EXISTS (SELECT 1 FROM class_members WHERE user_name = session_user
                                     AND role = 'coordinator' AND withdrawn_at IS NULL) THEN
    RAISE EXCEPTION '% is no class''s coordinator now; only a current coordinator writes to a study', session_user
      USING ERRCODE = 'insufficient_privilege';
  END IF;
END
$f$;

CREATE OR REPLACE FUNCTION at_study_for_writer(p_study text) RETURNS jsonb LANGUAGE plpgsql STABLE AS $f$
DECLARE
  s studies%ROWTYPE;
BEGIN
  SELECT * INTO s FROM studies WHERE id = p_study;
  IF at_is_account() AND (NOT FOUND OR s.owner IS DISTINCT FROM session_user) THEN
    RAISE EXCEPTION '% owns no study ''%'' on the class server; only a study''s coordinator records its participants',
      session_user, p_study USING ERRCODE = 'insufficient_privilege';
  END IF;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'no study ''%'' on the class server', p_study USING ERRCODE = 'no_data_found';
  END IF;
  PERFORM at_require_current_coordinator();
  RETURN s.json::jsonb;
END
$f$;

-- Unsigned 64-bit words as numeric (0 … 2^64 - 1) and as bit(64).
CREATE FUNCTION at_u64_bits(u numeric) RETURNS bit(64) LANGUAGE sql IMMUTABLE AS $f$
  SELECT (CASE WHEN u >= 9223372036854775808 THEN u - 18446744073709551616 ELSE u END)::bigint::bit(64)
$f$;
CREATE FUNCTION at_bits_u64(b bit(64)) RETURNS numeric LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE WHEN b::bigint < 0 THEN b::bigint::numeric + 18446744073709551616 ELSE b::bigint::numeric END
$f$;

-- quiz's splitmix64: advances `state` and returns the next value.
CREATE FUNCTION at_splitmix64(INOUT state numeric, OUT value numeric) LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  z numeric;
BEGIN
  state := mod(state + 11400714819323198485, 18446744073709551616);
  z := state;
  z := mod(at_bits_u64(at_u64_bits(z) # (at_u64_bits(z) >> 30)) * 13787848793156543929, 18446744073709551616);
  z := mod(at_bits_u64(at_u64_bits(z) # (at_u64_bits(z) >> 27)) * 10723151780598845931, 18446744073709551616);
  value := at_bits_u64(at_u64_bits(z) # (at_u64_bits(z) >> 31));
END
$f$;

-- quiz::planParticipant(n, participant, seed): per position, the index of the structure shown and
-- whether condition 0 is shown as A (slot: the position; "position" is a word of SQL).
CREATE FUNCTION at_study_plan(n integer, participant bigint, seed numeric)
RETURNS TABLE (slot integer, structure_index integer, a_is_first boolean) LANGUAGE plpgsql IMMUTABLE AS $f$
DECLARE
  permutation integer[];
  first integer[] := ARRAY[0];
  step integer := 1;
  state numeric := mod(seed, 18446744073709551616);
  drawn numeric;
  j integer;
  swap integer;
  in_cycle integer;
  item integer;
BEGIN
  IF n <= 0 THEN RETURN; END IF;
  SELECT array_agg(i ORDER BY i) INTO permutation FROM generate_series(0, n - 1) i;
  FOR i IN REVERSE n - 1..1 LOOP  -- Fisher–Yates (arrays here are 1-based)
    SELECT s.state, s.value INTO state, drawn FROM at_splitmix64(state) s;
    j := mod(drawn, i + 1)::integer;
    swap := permutation[i + 1];
    permutation[i + 1] := permutation[j + 1];
    permutation[j + 1] := swap;
  END LOOP;
  WHILE array_length(first, 1) < n LOOP  -- the Williams square's first row: 0, 1, n-1, 2, n-2, …
    first := first || step;
    IF array_length(first, 1) < n THEN first := first || (n - step); END IF;
    step := step + 1;
  END LOOP;
  in_cycle := mod(participant, CASE WHEN n % 2 = 0 THEN n ELSE 2 * n END)::integer;
  FOR p IN 0..n - 1 LOOP
    item := CASE WHEN in_cycle < n THEN (first[p + 1] + in_cycle) % n   -- row in_cycle
                 ELSE (first[n - p] + in_cycle - n) % n END;            -- the mirrored square
    slot := p;
    structure_index := permutation[item + 1];
    a_is_first := (in_cycle + item) % 2 = 0;
    RETURN NEXT;
  END LOOP;
END
$f$;

ALTER FUNCTION at_enrol_participant(text, text, text, bigint, text) RENAME TO at_enrol_participant_unchecked;

-- at_enrol_participant (study_writes_sql.cpp) after two more checks for a new participant: row
-- p_index goes to no one else, and the trials sent are that row of the design.
CREATE FUNCTION at_enrol_participant(p_study text, p_participant text, p_group text, p_index bigint, p_trials text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  design jsonb := at_study_for_writer(p_study);
  trials jsonb;
  n integer := jsonb_array_length(design->'structures');
  taken text;
  mismatch integer;
BEGIN
  IF p_index IS NOT NULL AND NOT EXISTS (SELECT 1 FROM study_participants WHERE study_id = p_study
                                         AND participant_id = p_participant) THEN
    SELECT participant_id INTO taken FROM study_participants WHERE study_id = p_study AND enrolment_index = p_index;
    IF FOUND THEN
      RAISE EXCEPTION 'study ''%'': row % of its counterbalancing is participant ''%''''s; draw a new one for ''%''', p_study,
        p_index, taken, p_participant USING ERRCODE = 'invalid_parameter_value';
    END IF;
    BEGIN
      trials := p_trials::jsonb;
    EXCEPTION WHEN others THEN
      trials := NULL;
    END;
    IF jsonb_typeof(trials) = 'array' THEN
      SELECT count(*) INTO mismatch
      FROM at_study_plan(n, p_index, (design->>'seed')::numeric) plan
      WHERE NOT EXISTS (
        SELECT 1 FROM jsonb_array_elements(trials) t
        WHERE jsonb_typeof(t->'position') = 'number' AND (t->>'position') = plan.slot::text
          AND t->>'structure' IS NOT DISTINCT FROM design->'structures'->>plan.structure_index
          AND t->>'a_condition' IS NOT DISTINCT FROM design->'conditions'->(CASE WHEN plan.a_is_first THEN 0 ELSE 1 END)->>'id');
      IF mismatch > 0 OR jsonb_array_length(trials) <> n THEN
        RAISE EXCEPTION 'study ''%'': the trials sent for participant ''%'' are not row % of its counterbalancing, which the server drew (% of % trials differ); nothing was enrolled',
          p_study, p_participant, p_index, greatest(mismatch, abs(jsonb_array_length(trials) - n)), n
          USING ERRCODE = 'invalid_parameter_value';
      END IF;
    END IF;  -- not an array: at_enrol_participant_unchecked refuses it
  END IF;
  RETURN at_enrol_participant_unchecked(p_study, p_participant, p_group, p_index, p_trials);
END
$f$;

CREATE OR REPLACE FUNCTION at_withdraw_participant(p_study text, p_participant text, p_kind text, p_reason text, p_by text)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  study_owner text;
BEGIN
  SELECT owner INTO study_owner FROM studies WHERE id = p_study;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'no study ''%'' on the class server', p_study USING ERRCODE = 'no_data_found';
  END IF;
  IF (at_is_account() AND study_owner IS DISTINCT FROM actor)
     OR (NOT at_is_account() AND study_owner <> '' AND coalesce(p_by, '') <> '' AND study_owner <> actor) THEN
    RAISE EXCEPTION '''%'' does not own study ''%''; only its coordinator (%) withdraws or excludes its participants',
      actor, p_study, CASE WHEN study_owner = '' THEN 'the administrator' ELSE study_owner END
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  PERFORM at_require_current_coordinator();
  IF p_kind NOT IN ('withdrawn', 'excluded') THEN
    RAISE EXCEPTION 'a participant is withdrawn or excluded, not %', p_kind USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_reason IS NULL OR btrim(p_reason) = '' THEN
    RAISE EXCEPTION 'a withdrawal or exclusion needs its reason' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  UPDATE study_participants
  SET withdrawn_at = to_char(clock_timestamp() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS.MS"Z"'),
      withdrawal_kind = p_kind, withdrawal_reason = p_reason
  WHERE study_id = p_study AND participant_id = p_participant AND withdrawn_at IS NULL;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'study ''%'' has no current participant ''%''', p_study, p_participant USING ERRCODE = 'no_data_found';
  END IF;
  PERFORM at_audit(actor, 'study_' || p_kind, '', p_study || ' ' || p_participant, 'participant', p_kind, p_reason);
END
$f$;

-- A participant merged in from another machine's database or export (`study merge` into a class
-- server): their row, trials and ratings as that machine recorded them (p_records: {participant:
-- {column: value}, trials: [{column: value}], ratings: [...]}; withdrawal columns included), written
-- by the study's current coordinator (or the administrator) only, on a new enrolment row, and
-- audited (study_merged: the records' md5, the source's name). Trials must show the study's
-- structures with its two conditions as A and B; ratings its items on its scale, of those trials.
-- A participant already there is refused: the program compares and skips the same records.
CREATE FUNCTION at_merge_participant(p_study text, p_participant text, p_records text, p_source text) RETURNS bigint
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  design jsonb := at_study_for_writer(p_study);
  r jsonb;
  ids jsonb := jsonb_build_object('study_id', p_study, 'participant_id', p_participant);
  row_index bigint;
BEGIN
  BEGIN
    r := p_records::jsonb;
  EXCEPTION WHEN others THEN
    r := NULL;
  END;
  IF jsonb_typeof(r->'participant') IS DISTINCT FROM 'object' OR jsonb_typeof(r->'trials') IS DISTINCT FROM 'array'
     OR jsonb_typeof(r->'ratings') IS DISTINCT FROM 'array' THEN
    RAISE EXCEPTION 'study ''%'': the records of participant ''%'' are not {participant, trials, ratings}', p_study,
      p_participant USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_participant IS NULL OR p_participant !~ '^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$' THEN
    RAISE EXCEPTION 'participant id ''%'' must be 1 to 64 letters, digits, ''_'' or ''-'', starting with a letter or digit',
      p_participant USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF EXISTS (SELECT 1 FROM study_participants WHERE study_id = p_study AND participant_id = p_participant) THEN
    RAISE EXCEPTION 'study ''%'' already has participant ''%''; nothing was merged', p_study, p_participant
      USING ERRCODE = 'unique_violation';
  END IF;
  IF NOT (design->'groups') ? (r->'participant'->>'group_name')
     OR EXISTS (SELECT 1 FROM jsonb_array_elements(r->'trials') t
                WHERE NOT (design->'structures') ? (t->>'structure')
                   OR t->>'a_condition' IS NOT DISTINCT FROM t->>'b_condition'
                   OR NOT EXISTS (SELECT 1 FROM jsonb_array_elements(design->'conditions') c WHERE c->>'id' = t->>'a_condition')
                   OR NOT EXISTS (SELECT 1 FROM jsonb_array_elements(design->'conditions') c WHERE c->>'id' = t->>'b_condition'))
     OR EXISTS (SELECT 1 FROM jsonb_array_elements(r->'ratings') g
                WHERE NOT EXISTS (SELECT 1 FROM jsonb_array_elements(design->'items') i WHERE i->>'id' = g->>'item')
                   OR jsonb_typeof(g->'rating_ab') IS DISTINCT FROM 'number'
                   OR (g->>'rating_ab')::numeric < (design->'scale'->>'min')::numeric
                   OR (g->>'rating_ab')::numeric > (design->'scale'->>'max')::numeric) THEN
    RAISE EXCEPTION 'study ''%'': participant ''%'' comes with a group, a trial or a rating outside the study''s design; nothing was merged',
      p_study, p_participant USING ERRCODE = 'invalid_parameter_value';
  END IF;
  UPDATE studies SET next_enrolment = GREATEST(next_enrolment, (SELECT coalesce(max(enrolment_index) + 1, 0)
    FROM study_participants WHERE study_id = p_study)) + 1 WHERE id = p_study RETURNING next_enrolment - 1 INTO row_index;
  INSERT INTO study_participants
  SELECT * FROM jsonb_populate_record(NULL::study_participants, r->'participant' || ids || jsonb_build_object('enrolment_index', row_index));
  INSERT INTO study_trials
  SELECT * FROM jsonb_populate_recordset(NULL::study_trials, (SELECT jsonb_agg(t || ids) FROM jsonb_array_elements(r->'trials') t));
  INSERT INTO study_ratings
  SELECT * FROM jsonb_populate_recordset(NULL::study_ratings, (SELECT jsonb_agg(g || ids) FROM jsonb_array_elements(r->'ratings') g));
  PERFORM at_audit(session_user, 'study_merged', '', p_study || ' ' || p_participant, NULL, md5(p_records),
                   coalesce(p_source, ''));
  RETURN row_index;
END
$f$;

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef, p.proname FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_require_current_coordinator', 'at_study_for_writer',
             'at_u64_bits', 'at_bits_u64', 'at_splitmix64', 'at_study_plan', 'at_enrol_participant',
             'at_enrol_participant_unchecked', 'at_withdraw_participant', 'at_merge_participant') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef AND t.proname <> 'at_enrol_participant_unchecked' THEN
      EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn);
    ELSE
      EXECUTE format('REVOKE ALL ON FUNCTION %s FROM at_class_member', t.fn);
    END IF;
  END LOOP;
END
$own$;
)SQL";
}

}  // namespace at::db
