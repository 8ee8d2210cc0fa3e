// Studies on a class server, PostgreSQL only:
//
//  - a study has an owner (studies.owner: the coordinator's login, set when it is registered);
//    through row-level security that login, and no other, reads the study, its participants,
//    their blinded trials (the A/B keys) and their ratings — what `study status` and `study
//    export` need. Participants and students read none of it. Nobody's login writes these tables.
//  - at_withdraw_participant: the owner withdraws a participant (consent withdrawn) or excludes
//    them, with the reason; the participant's rows stay but every export and Table 2 leave them
//    out; the change goes into class_audit (action study_withdrawn / study_excluded, target
//    "<study> <participant>"), which the study's owner reads.
#include "study_security_sql.h"

namespace at::db {

std::string_view studySecuritySql() {
  return R"SQL(
CREATE FUNCTION at_owns_study(p_study text) RETURNS boolean LANGUAGE sql STABLE SECURITY DEFINER AS $f$
  SELECT EXISTS (SELECT 1 FROM studies WHERE id = p_study AND owner = session_user AND owner <> '')
$f$;

CREATE FUNCTION at_withdraw_participant(p_study text, p_participant text, p_kind text, p_reason text, p_by text)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  study_owner text;
BEGIN
  SELECT owner INTO study_owner FROM studies WHERE id = p_study;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'no study ''%'' on the class server', p_study USING ERRCODE = 'no_data_found';
  END IF;
  -- A login must own the study; the administrator may act for its owner (or for anyone while the
  -- study has none).
  IF (at_is_account() AND study_owner IS DISTINCT FROM actor)
     OR (NOT at_is_account() AND study_owner <> '' AND coalesce(p_by, '') <> '' AND study_owner <> actor) THEN
    RAISE EXCEPTION '''%'' does not own study ''%''; only its coordinator (%) withdraws or excludes its participants',
      actor, p_study, CASE WHEN study_owner = '' THEN 'the administrator' ELSE study_owner END
      USING ERRCODE = 'insufficient_privilege';
  END IF;
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

ALTER TABLE studies ENABLE ROW LEVEL SECURITY;
ALTER TABLE study_participants ENABLE ROW LEVEL SECURITY;
ALTER TABLE study_trials ENABLE ROW LEVEL SECURITY;
ALTER TABLE study_ratings ENABLE ROW LEVEL SECURITY;
CREATE POLICY owner_reads ON studies FOR SELECT TO at_class_member USING (owner <> '' AND owner = session_user);
CREATE POLICY owner_reads ON study_participants FOR SELECT TO at_class_member USING (at_owns_study(study_id));
CREATE POLICY owner_reads ON study_trials FOR SELECT TO at_class_member USING (at_owns_study(study_id));
CREATE POLICY owner_reads ON study_ratings FOR SELECT TO at_class_member USING (at_owns_study(study_id));
CREATE POLICY study_owner_reads ON class_audit FOR SELECT TO at_class_member
  USING (action LIKE 'study\_%' AND at_owns_study(split_part(target, ' ', 1)));

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname IN ('at_owns_study', 'at_withdraw_participant') LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn);
  END LOOP;
  EXECUTE format('GRANT SELECT ON %I.studies, %I.study_participants, %I.study_trials, %I.study_ratings TO at_class_member',
                 schema_name, schema_name, schema_name, schema_name);
END
$own$;
)SQL";
}

}  // namespace at::db
