// How a study is written on a class server, PostgreSQL only. No login holds INSERT, UPDATE or
// DELETE on the study tables; a coordinator's login registers a study and records its participants
// through these SECURITY DEFINER functions (search_path pinned to this schema, then pg_temp), which
// act as `session_user`:
//
//  - at_register_study: stores or updates a study's protocol. A login must be a current
//    coordinator of some class; the study becomes (and stays) that login's. A login cannot name
//    another owner, nor update a study it does not own; a study with participants keeps its design
//    (structures, conditions, presets, items, scale, seed). Audited (study_registered).
//  - at_set_study_owner: the owner (or the administrator) hands the study to another coordinator's
//    login. Audited (study_owner).
//  - at_draw_study_row, at_enrol_participant: the next counterbalancing row, then the participant
//    with their blinded trials (one per structure, each condition once as A or B, the presets the
//    protocol names), or a resume of one already enrolled (session + 1).
//  - at_record_rating, at_record_trial_viewing, at_complete_participant: a participant's writes,
//    refused unless from the participant's latest session and while they are not withdrawn; a
//    rating is one of the study's items on its scale. A rating replaced by another value is
//    audited (study_rerated: old and new value).
//
// Only the study's owner may call them for it (or the administrator, which is no class login);
// any other login — a student, an instructor, another coordinator — is refused with the same
// message whether the study exists or not, and nothing is written. Participants are pseudonyms,
// not logins: they read nothing of any study (study_security_sql.cpp).
#include "study_writes_sql.h"

namespace at::db {

std::string_view studyWritesSql() {
  return R"SQL(
-- Inside the functions below: the protocol of study `p_study`, which this connection may write (its
-- owner's login, or the administrator).
CREATE FUNCTION at_study_for_writer(p_study text) RETURNS jsonb LANGUAGE plpgsql STABLE AS $f$
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
  RETURN s.json::jsonb;
END
$f$;

-- Inside the functions below: fails unless the participant is enrolled, not withdrawn, and
-- `p_session` is their latest session.
CREATE FUNCTION at_require_current_session(p_study text, p_participant text, p_session bigint) RETURNS void
LANGUAGE plpgsql STABLE AS $f$
DECLARE
  p study_participants%ROWTYPE;
BEGIN
  SELECT * INTO p FROM study_participants WHERE study_id = p_study AND participant_id = p_participant;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'study ''%'' has no participant ''%''', p_study, p_participant USING ERRCODE = 'no_data_found';
  END IF;
  IF p.withdrawn_at IS NOT NULL THEN
    RAISE EXCEPTION 'participant ''%'' was % from study ''%'' (%); nothing more is recorded for them',
      p_participant, p.withdrawal_kind, p_study, p.withdrawal_reason USING ERRCODE = 'object_not_in_prerequisite_state';
  END IF;
  IF p_session IS DISTINCT FROM p.session THEN
    RAISE EXCEPTION 'study ''%'': participant ''%'' was resumed by another session (session %) after this one (session %) began',
      p_study, p_participant, p.session, coalesce(p_session::text, 'none') USING ERRCODE = 'object_not_in_prerequisite_state';
  END IF;
END
$f$;

CREATE FUNCTION at_register_study(p_id text, p_title text, p_dataset text, p_seed bigint, p_json text, p_owner text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  design jsonb;
  old studies%ROWTYPE;
  old_design jsonb;
  new_owner text;
  k text;
BEGIN
  IF at_is_account() THEN
    IF coalesce(p_owner, '') NOT IN ('', session_user) THEN
      RAISE EXCEPTION 'you are logged in to the class server as %; a study you register is yours, not %''s',
        session_user, p_owner USING ERRCODE = 'insufficient_privilege';
    END IF;
    IF NOT EXISTS (SELECT 1 FROM class_members WHERE user_name = session_user AND role = 'coordinator'
                   AND withdrawn_at IS NULL) THEN
      RAISE EXCEPTION '% is no class''s coordinator; only coordinators register studies', session_user
        USING ERRCODE = 'insufficient_privilege';
    END IF;
  END IF;
  BEGIN
    design := p_json::jsonb;
  EXCEPTION WHEN others THEN
    RAISE EXCEPTION 'study ''%'': its protocol is not JSON', p_id USING ERRCODE = 'invalid_parameter_value';
  END;
  -- The audit names a study's rows by "<study> …": an id has no space, so no study's audit reads
  -- as another's.
  IF p_id IS NULL OR p_id !~ '^[^[:space:]]+$' OR jsonb_typeof(design) IS DISTINCT FROM 'object' OR design->>'id' IS DISTINCT FROM p_id
     OR design->>'dataset' IS DISTINCT FROM p_dataset OR coalesce(design->>'title', '') <> coalesce(p_title, '')
     OR (design->>'seed')::numeric IS DISTINCT FROM p_seed::numeric AND p_seed >= 0
     OR jsonb_typeof(design->'structures') IS DISTINCT FROM 'array' OR jsonb_array_length(design->'structures') = 0
     OR jsonb_typeof(design->'conditions') IS DISTINCT FROM 'array' OR jsonb_array_length(design->'conditions') <> 2
     OR design->'conditions'->0->>'id' IS NULL OR design->'conditions'->0->>'id' = design->'conditions'->1->>'id'
     OR jsonb_typeof(design->'items') IS DISTINCT FROM 'array' OR jsonb_array_length(design->'items') = 0
     OR jsonb_typeof(design->'groups') IS DISTINCT FROM 'array' OR jsonb_array_length(design->'groups') = 0
     OR jsonb_typeof(design->'scale'->'min') IS DISTINCT FROM 'number'
     OR jsonb_typeof(design->'scale'->'max') IS DISTINCT FROM 'number' THEN
    RAISE EXCEPTION 'study ''%'': its id has a space, or its protocol does not name the same id, title, dataset and seed, or lacks its structures, two conditions, items, groups or scale',
      p_id USING ERRCODE = 'invalid_parameter_value';
  END IF;
  SELECT * INTO old FROM studies WHERE id = p_id FOR UPDATE;
  IF FOUND THEN
    IF at_is_account() AND old.owner IS DISTINCT FROM session_user THEN
      RAISE EXCEPTION 'study ''%'' is already on the class server and is not yours (give your study another id)', p_id
        USING ERRCODE = 'insufficient_privilege';
    END IF;
    old_design := old.json::jsonb;
    IF EXISTS (SELECT 1 FROM study_participants WHERE study_id = p_id) THEN
      FOREACH k IN ARRAY ARRAY['structures', 'conditions', 'presets', 'items', 'scale', 'seed'] LOOP
        IF design->k IS DISTINCT FROM old_design->k THEN
          RAISE EXCEPTION 'study ''%'' already has % participant(s); its structures, conditions, items, scale and seed cannot change (give the new design another id)',
            p_id, (SELECT count(*) FROM study_participants WHERE study_id = p_id) USING ERRCODE = 'invalid_parameter_value';
        END IF;
      END LOOP;
    END IF;
    new_owner := CASE WHEN at_is_account() THEN old.owner ELSE coalesce(nullif(p_owner, ''), old.owner) END;
    UPDATE studies SET title = coalesce(p_title, ''), dataset = p_dataset, seed = p_seed, json = p_json, owner = new_owner
    WHERE id = p_id;
    IF old.json IS DISTINCT FROM p_json OR old.owner IS DISTINCT FROM new_owner THEN
      PERFORM at_audit(session_user, 'study_registered', '', p_id, old.owner || ' ' || md5(old.json),
                       new_owner || ' ' || md5(p_json), 'updated');
    END IF;
    RETURN 'updated';
  END IF;
  new_owner := CASE WHEN at_is_account() THEN session_user ELSE coalesce(p_owner, '') END;
  INSERT INTO studies (id, title, dataset, seed, json, owner) VALUES (p_id, coalesce(p_title, ''), p_dataset, p_seed, p_json, new_owner);
  PERFORM at_audit(session_user, 'study_registered', '', p_id, NULL, new_owner || ' ' || md5(p_json), 'registered');
  RETURN 'stored';
END
$f$;

CREATE FUNCTION at_set_study_owner(p_study text, p_owner text) RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  old_owner text;
BEGIN
  PERFORM at_study_for_writer(p_study);
  SELECT owner INTO old_owner FROM studies WHERE id = p_study FOR UPDATE;
  IF at_is_account() AND NOT EXISTS (SELECT 1 FROM class_members WHERE user_name = p_owner AND role = 'coordinator'
                                     AND withdrawn_at IS NULL) THEN
    RAISE EXCEPTION '''%'' is no class''s coordinator; a study goes only to a coordinator''s login', p_owner
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  IF old_owner IS NOT DISTINCT FROM coalesce(p_owner, '') THEN RETURN; END IF;
  UPDATE studies SET owner = coalesce(p_owner, '') WHERE id = p_study;
  PERFORM at_audit(session_user, 'study_owner', '', p_study, old_owner, coalesce(p_owner, ''), '');
END
$f$;

CREATE FUNCTION at_draw_study_row(p_study text) RETURNS bigint LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  drawn bigint;
BEGIN
  PERFORM at_study_for_writer(p_study);
  UPDATE studies SET next_enrolment = GREATEST(next_enrolment, (SELECT coalesce(max(enrolment_index) + 1, 0)
    FROM study_participants WHERE study_id = p_study)) + 1 WHERE id = p_study RETURNING next_enrolment - 1 INTO drawn;
  RETURN drawn;
END
$f$;

-- 'enrolled' (with the trials given: one per structure, in positions 0…n-1, each showing the two
-- conditions as A and B with the presets the protocol names) or 'resumed' (session + 1).
CREATE FUNCTION at_enrol_participant(p_study text, p_participant text, p_group text, p_index bigint, p_trials text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  design jsonb := at_study_for_writer(p_study);
  p study_participants%ROWTYPE;
  trials jsonb;
  t jsonb;
  n int := jsonb_array_length(design->'structures');
  a int;
  b int;
  s text;
BEGIN
  IF p_participant IS NULL OR p_participant !~ '^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$' THEN
    RAISE EXCEPTION 'participant id ''%'' must be 1 to 64 letters, digits, ''_'' or ''-'', starting with a letter or digit',
      p_participant USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_group IS NULL OR NOT (design->'groups') ? p_group THEN
    RAISE EXCEPTION 'group ''%'' is not one of study ''%''''s groups', p_group, p_study USING ERRCODE = 'invalid_parameter_value';
  END IF;
  SELECT * INTO p FROM study_participants WHERE study_id = p_study AND participant_id = p_participant FOR UPDATE;
  IF FOUND THEN
    IF p.withdrawn_at IS NOT NULL THEN
      RAISE EXCEPTION 'participant ''%'' was % from study ''%'' (%); nothing more is recorded for them',
        p_participant, p.withdrawal_kind, p_study, p.withdrawal_reason USING ERRCODE = 'object_not_in_prerequisite_state';
    END IF;
    IF p.group_name <> p_group THEN
      RAISE EXCEPTION 'participant ''%'' is enrolled in group ''%'', not ''%''', p_participant, p.group_name, p_group
        USING ERRCODE = 'invalid_parameter_value';
    END IF;
    UPDATE study_participants SET session = session + 1 WHERE study_id = p_study AND participant_id = p_participant;
    RETURN 'resumed';
  END IF;
  IF p_index IS NULL OR p_index < 0 OR p_index >= (SELECT next_enrolment FROM studies WHERE id = p_study) THEN
    RAISE EXCEPTION 'study ''%'': row % was not drawn for enrolment (at_draw_study_row draws it)', p_study,
      coalesce(p_index::text, 'NULL') USING ERRCODE = 'invalid_parameter_value';
  END IF;
  BEGIN
    trials := p_trials::jsonb;
  EXCEPTION WHEN others THEN
    trials := NULL;
  END;
  IF jsonb_typeof(trials) IS DISTINCT FROM 'array' OR jsonb_array_length(trials) <> n
     OR (SELECT count(DISTINCT e->>'structure') FROM jsonb_array_elements(trials) e
         WHERE (design->'structures') ? (e->>'structure')) <> n
     OR (SELECT count(DISTINCT (e->>'position')) FROM jsonb_array_elements(trials) e
         WHERE jsonb_typeof(e->'position') = 'number' AND (e->>'position') ~ '^[0-9]+$' AND (e->>'position')::int < n) <> n THEN
    RAISE EXCEPTION 'study ''%'': the trials of participant ''%'' must show each of its % structures once, in positions 0 to %',
      p_study, p_participant, n, n - 1 USING ERRCODE = 'invalid_parameter_value';
  END IF;
  INSERT INTO study_participants (study_id, participant_id, group_name, enrolment_index)
  VALUES (p_study, p_participant, p_group, p_index);
  FOR t IN SELECT e FROM jsonb_array_elements(trials) e LOOP
    s := t->>'structure';
    a := CASE t->>'a_condition' WHEN design->'conditions'->0->>'id' THEN 0 WHEN design->'conditions'->1->>'id' THEN 1 END;
    b := CASE t->>'b_condition' WHEN design->'conditions'->0->>'id' THEN 0 WHEN design->'conditions'->1->>'id' THEN 1 END;
    IF a IS NULL OR b IS NULL OR a = b
       OR t->>'preset_a' IS DISTINCT FROM coalesce(design->'presets'->s->>a, s || coalesce(design->'conditions'->a->>'preset_suffix', ''))
       OR t->>'preset_b' IS DISTINCT FROM coalesce(design->'presets'->s->>b, s || coalesce(design->'conditions'->b->>'preset_suffix', '')) THEN
      RAISE EXCEPTION 'study ''%'': the trial of % for participant ''%'' must show its two conditions as A and B with their presets',
        p_study, s, p_participant USING ERRCODE = 'invalid_parameter_value';
    END IF;
    INSERT INTO study_trials (study_id, participant_id, position, structure, a_condition, b_condition, preset_a, preset_b)
    VALUES (p_study, p_participant, (t->>'position')::int, s, t->>'a_condition', t->>'b_condition', t->>'preset_a',
            t->>'preset_b');
  END LOOP;
  RETURN 'enrolled';
END
$f$;

CREATE FUNCTION at_record_rating(p_study text, p_participant text, p_session bigint, p_position bigint, p_item text,
                                 p_rating bigint, p_response_ms double precision, p_t double precision,
                                 p_alpha double precision, p_beta double precision, p_app_version text,
                                 p_quality_level bigint, p_quality_full_level bigint,
                                 p_quality_scale double precision, p_settle_ms double precision)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  design jsonb := at_study_for_writer(p_study);
  earlier bigint;
BEGIN
  PERFORM at_require_current_session(p_study, p_participant, p_session);
  IF NOT EXISTS (SELECT 1 FROM jsonb_array_elements(design->'items') i WHERE i->>'id' = p_item) THEN
    RAISE EXCEPTION 'study ''%'' has no item ''%''', p_study, p_item USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_rating IS NULL OR p_rating < (design->'scale'->>'min')::numeric OR p_rating > (design->'scale'->>'max')::numeric THEN
    RAISE EXCEPTION 'study ''%'': rating % is off its scale (% to %)', p_study, coalesce(p_rating::text, 'NULL'),
      design->'scale'->>'min', design->'scale'->>'max' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF NOT EXISTS (SELECT 1 FROM study_trials WHERE study_id = p_study AND participant_id = p_participant AND position = p_position) THEN
    RAISE EXCEPTION 'study ''%'': participant ''%'' has no trial %', p_study, p_participant, p_position
      USING ERRCODE = 'no_data_found';
  END IF;
  SELECT rating_ab INTO earlier FROM study_ratings
  WHERE study_id = p_study AND participant_id = p_participant AND position = p_position AND item = p_item;
  INSERT INTO study_ratings (study_id, participant_id, position, item, rating_ab, response_ms, t, alpha, beta, app_version,
                             session, created_at, quality_level, quality_full_level, quality_scale, settle_ms)
  VALUES (p_study, p_participant, p_position, p_item, p_rating, coalesce(p_response_ms, 0), coalesce(p_t, 0),
          coalesce(p_alpha, 0), coalesce(p_beta, 0), coalesce(p_app_version, ''), p_session,
          to_char(clock_timestamp() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS.MS"Z"'), p_quality_level,
          p_quality_full_level, p_quality_scale, p_settle_ms)
  ON CONFLICT (study_id, participant_id, position, item) DO UPDATE SET rating_ab = excluded.rating_ab,
    response_ms = excluded.response_ms, t = excluded.t, alpha = excluded.alpha, beta = excluded.beta,
    app_version = excluded.app_version, session = excluded.session, created_at = excluded.created_at,
    quality_level = excluded.quality_level, quality_full_level = excluded.quality_full_level,
    quality_scale = excluded.quality_scale, settle_ms = excluded.settle_ms;
  IF earlier IS NOT NULL AND earlier <> p_rating THEN
    PERFORM at_audit(session_user, 'study_rerated', '', p_study || ' ' || p_participant || ' ' || p_position || ' ' || p_item,
                     earlier::text, p_rating::text, 'session ' || p_session);
  END IF;
END
$f$;

CREATE FUNCTION at_record_trial_viewing(p_study text, p_participant text, p_session bigint, p_position bigint,
                                        p_view_ms_a double precision, p_view_ms_b double precision, p_toggles bigint,
                                        p_comment text, p_measured bigint)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
BEGIN
  PERFORM at_study_for_writer(p_study);
  PERFORM at_require_current_session(p_study, p_participant, p_session);
  IF p_measured NOT IN (0, 1) OR p_measured = 1 AND (p_view_ms_a IS NULL OR p_view_ms_a < 0 OR p_view_ms_b IS NULL
     OR p_view_ms_b < 0 OR p_toggles IS NULL OR p_toggles < 0) THEN
    RAISE EXCEPTION 'study ''%'': viewing times and toggles are measured (not negative) or blank', p_study
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  UPDATE study_trials SET view_ms_a = CASE WHEN p_measured = 1 THEN p_view_ms_a END,
                          view_ms_b = CASE WHEN p_measured = 1 THEN p_view_ms_b END,
                          toggles = CASE WHEN p_measured = 1 THEN p_toggles ELSE 0 END,
                          comment = nullif(p_comment, ''), viewing_measured = p_measured
  WHERE study_id = p_study AND participant_id = p_participant AND position = p_position;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'study ''%'': participant ''%'' has no trial %', p_study, p_participant, p_position
      USING ERRCODE = 'no_data_found';
  END IF;
END
$f$;

CREATE FUNCTION at_complete_participant(p_study text, p_participant text, p_session bigint) RETURNS void
LANGUAGE plpgsql SECURITY DEFINER AS $f$
BEGIN
  PERFORM at_study_for_writer(p_study);
  PERFORM at_require_current_session(p_study, p_participant, p_session);
  UPDATE study_participants SET completed_at = to_char(clock_timestamp() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS.MS"Z"')
  WHERE study_id = p_study AND participant_id = p_participant AND completed_at IS NULL;
END
$f$;

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_study_for_writer', 'at_require_current_session',
             'at_register_study', 'at_set_study_owner', 'at_draw_study_row', 'at_enrol_participant', 'at_record_rating',
             'at_record_trial_viewing', 'at_complete_participant') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef THEN EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn); END IF;
  END LOOP;
END
$own$;
)SQL";
}

}  // namespace at::db
