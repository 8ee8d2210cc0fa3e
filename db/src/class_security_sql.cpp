// The class server's security, PostgreSQL only (a SQLite file is one person's laptop):
//
//  - roles (cluster-wide, made once): at_class_owner (NOLOGIN, CREATEROLE) owns every table and
//    function; at_class_member (NOLOGIN) is the group of every person's login, made by
//    at_create_account. The login that migrates (the administrator) is made a member of the
//    owner, so it keeps managing the database as before.
//  - a person's login reads through row-level security: their own class rows and events; an
//    instructor or coordinator also the rows of their classes; a coordinator the audit of their
//    classes. No login is granted INSERT, UPDATE, DELETE or TRUNCATE on any table, nor anything
//    on the curriculum, exams, studies (their A/B keys and ratings) or local tables.
//  - writes go through SECURITY DEFINER functions with search_path pinned to this schema (then
//    pg_temp): they act as `session_user` (a login can never name someone else) and record every
//    role change, withdrawal and correction in class_audit, which nobody can update or delete.
//  - at_record_event decides what counts: an outbox event is stored only when its UUID is well
//    formed, its sender is the login, a current member of the class, its question and lesson exist
//    on the server and the lesson is unlocked for that person (prerequisites finished; started
//    before its answers and its end, finished only with every question answered; a review answer
//    needs its question's lesson unlocked); otherwise it answers 'refused: <why>' and stores nothing.
//
// A connection that is not a person's login (the administrator: the database's owner or a
// superuser) may still act on a member's behalf, naming them — it owns the tables anyway.
#include "class_security_sql.h"

namespace at::db {

std::string_view classSecuritySql() {
  return R"SQL(
DO $roles$
BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'at_class_owner') THEN
    CREATE ROLE at_class_owner NOLOGIN CREATEROLE;
  END IF;
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'at_class_member') THEN
    CREATE ROLE at_class_member NOLOGIN;
  END IF;
  IF NOT (SELECT rolsuper FROM pg_roles WHERE rolname = current_user) THEN
    EXECUTE format('GRANT at_class_owner TO %I', current_user);
  END IF;
END
$roles$;

CREATE FUNCTION at_is_account() RETURNS boolean LANGUAGE sql STABLE SECURITY DEFINER AS $f$
  SELECT coalesce((SELECT NOT r.rolsuper AND EXISTS (
            SELECT 1 FROM pg_auth_members m JOIN pg_roles g ON g.oid = m.roleid
            WHERE m.member = r.oid AND g.rolname = 'at_class_member')
          FROM pg_roles r WHERE r.rolname = session_user), false)
$f$;

CREATE FUNCTION at_role_in(p_class text) RETURNS text LANGUAGE sql STABLE SECURITY DEFINER AS $f$
  SELECT role FROM class_members
  WHERE class_code = p_class AND user_name = session_user AND withdrawn_at IS NULL
$f$;

-- Who acts: the login, or for the administrator the name it gives. A login naming anyone else is
-- refused here, whatever the program sent.
CREATE FUNCTION at_actor(p_by text) RETURNS text LANGUAGE plpgsql STABLE AS $f$
BEGIN
  IF at_is_account() THEN
    IF p_by IS NOT NULL AND p_by <> '' AND p_by <> session_user THEN
      RAISE EXCEPTION 'you are logged in to the class server as %; you cannot act as %', session_user, p_by
        USING ERRCODE = 'insufficient_privilege';
    END IF;
    RETURN session_user;
  END IF;
  IF p_by IS NULL OR p_by = '' THEN RETURN session_user; END IF;
  RETURN p_by;
END
$f$;

CREATE FUNCTION at_require_coordinator(p_class text, p_actor text) RETURNS void LANGUAGE plpgsql STABLE AS $f$
DECLARE
  r text;
BEGIN
  IF NOT EXISTS (SELECT 1 FROM classes WHERE code = p_class) THEN
    RAISE EXCEPTION 'no class has the code %', p_class USING ERRCODE = 'no_data_found';
  END IF;
  SELECT role INTO r FROM class_members WHERE class_code = p_class AND user_name = p_actor AND withdrawn_at IS NULL;
  IF r IS DISTINCT FROM 'coordinator' THEN
    RAISE EXCEPTION '''%'' is % of class %; only its coordinators give roles, make accounts, withdraw members and correct answers', p_actor,
      coalesce(r, 'not a member'), p_class USING ERRCODE = 'insufficient_privilege';
  END IF;
END
$f$;

-- Only the functions above and below call it (it is no login's to execute).
CREATE FUNCTION at_audit(p_actor text, p_action text, p_class text, p_target text, p_old text, p_new text,
                         p_reason text)
RETURNS void LANGUAGE sql AS $f$
  INSERT INTO class_audit (actor, login, action, class_code, target, old_value, new_value, reason)
  VALUES (p_actor, session_user, p_action, p_class, p_target, p_old, p_new, coalesce(p_reason, ''))
$f$;

-- Makes the login `p_name` (when there is none) and a member of the class with `p_role`. A login
-- that exists keeps its password (no one resets another person's password here); a role that is
-- not a class login (the administrator, postgres, …) is refused. Returns 'created' or 'existing'.
CREATE FUNCTION at_create_account(p_class text, p_name text, p_role text, p_password text, p_by text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  old_role text;
  outcome text := 'existing';
BEGIN
  IF at_is_account() OR p_by IS NOT NULL AND p_by <> '' THEN
    PERFORM at_require_coordinator(p_class, actor);
  ELSIF NOT EXISTS (SELECT 1 FROM classes WHERE code = p_class) THEN
    RAISE EXCEPTION 'no class has the code %', p_class USING ERRCODE = 'no_data_found';
  END IF;
  IF p_name !~ '^[a-z][a-z0-9_]{1,47}$' OR p_name LIKE 'at\_class\_%' OR p_name LIKE 'pg\_%' THEN
    RAISE EXCEPTION 'login name ''%'' must be 2 to 48 lower-case letters, digits and _, starting with a letter',
      p_name USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_role NOT IN ('student', 'instructor', 'coordinator') THEN
    RAISE EXCEPTION 'role ''%'' is not one of student, instructor, coordinator', p_role
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF EXISTS (SELECT 1 FROM pg_roles WHERE rolname = p_name) THEN
    IF NOT EXISTS (SELECT 1 FROM pg_auth_members m JOIN pg_roles g ON g.oid = m.roleid JOIN pg_roles u ON u.oid = m.member
                   WHERE g.rolname = 'at_class_member' AND u.rolname = p_name) THEN
      RAISE EXCEPTION 'the server already has a login ''%'' that is not a class account; choose another name', p_name
        USING ERRCODE = 'duplicate_object';
    END IF;
  ELSE
    IF p_password IS NULL OR length(p_password) < 16 THEN
      RAISE EXCEPTION 'a new login needs a password of at least 16 characters' USING ERRCODE = 'invalid_parameter_value';
    END IF;
    EXECUTE format('CREATE ROLE %I LOGIN PASSWORD %L IN ROLE at_class_member', p_name, p_password);
    outcome := 'created';
    PERFORM at_audit(actor, 'account', p_class, p_name, NULL, 'login', '');
  END IF;
  SELECT role INTO old_role FROM class_members WHERE class_code = p_class AND user_name = p_name;
  IF NOT FOUND THEN
    INSERT INTO class_members (class_code, user_name, role, joined_at)
    VALUES (p_class, p_name, p_role, extract(epoch FROM now())::bigint);
    PERFORM at_audit(actor, 'member', p_class, p_name, NULL, p_role, '');
  ELSIF old_role <> p_role THEN
    UPDATE class_members SET role = p_role WHERE class_code = p_class AND user_name = p_name;
    PERFORM at_audit(actor, 'role', p_class, p_name, old_role, p_role, '');
  END IF;
  RETURN outcome;
END
$f$;

-- A coordinator gives a member (or a name new to the class) a role in it (audited: old and new).
CREATE FUNCTION at_set_role(p_class text, p_member text, p_role text, p_by text) RETURNS void
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  old_role text;
BEGIN
  PERFORM at_require_coordinator(p_class, actor);
  IF p_role NOT IN ('student', 'instructor', 'coordinator') THEN
    RAISE EXCEPTION 'role ''%'' is not one of student, instructor, coordinator', p_role
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_member IS NULL OR p_member = '' THEN
    RAISE EXCEPTION 'a member''s name must not be empty' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  SELECT role INTO old_role FROM class_members WHERE class_code = p_class AND user_name = p_member;
  IF NOT FOUND THEN  -- a name without a login yet: `class account` makes its login later
    INSERT INTO class_members (class_code, user_name, role, joined_at)
    VALUES (p_class, p_member, p_role, extract(epoch FROM now())::bigint);
  ELSIF old_role = p_role THEN
    RETURN;
  ELSE
    UPDATE class_members SET role = p_role WHERE class_code = p_class AND user_name = p_member;
  END IF;
  PERFORM at_audit(actor, 'role', p_class, p_member, old_role, p_role, '');
END
$f$;

-- Withdrawal (consent withdrawn) or exclusion of a member, by a coordinator or by the member
-- themselves; the reason is kept, the member's events stay (exports mark them).
CREATE FUNCTION at_withdraw(p_class text, p_member text, p_reason text, p_by text) RETURNS void
LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
BEGIN
  IF actor <> p_member THEN PERFORM at_require_coordinator(p_class, actor); END IF;
  IF p_reason IS NULL OR btrim(p_reason) = '' THEN
    RAISE EXCEPTION 'a withdrawal needs its reason' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  UPDATE class_members SET withdrawn_at = extract(epoch FROM now())::bigint, withdrawal_reason = p_reason
  WHERE class_code = p_class AND user_name = p_member AND withdrawn_at IS NULL;
  IF NOT FOUND THEN
    RAISE EXCEPTION '''%'' is not a current member of class %', p_member, p_class USING ERRCODE = 'no_data_found';
  END IF;
  PERFORM at_audit(actor, 'withdraw', p_class, p_member, 'member', 'withdrawn', p_reason);
END
$f$;

-- A coordinator corrects the grade of one stored event (audited: old and new).
CREATE FUNCTION at_correct_event(p_uuid text, p_correct bigint, p_score double precision, p_reason text, p_by text)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  actor text := at_actor(p_by);
  e class_events%ROWTYPE;
BEGIN
  SELECT * INTO e FROM class_events WHERE uuid = p_uuid;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'no class event has the id %', p_uuid USING ERRCODE = 'no_data_found';
  END IF;
  PERFORM at_require_coordinator(e.class_code, actor);
  IF e.kind <> 'answer' OR p_correct NOT IN (0, 1) OR p_score < 0 OR p_score > 1 THEN
    RAISE EXCEPTION 'only answers are corrected, to correct 0 or 1 and a score from 0 to 1'
      USING ERRCODE = 'invalid_parameter_value';
  END IF;
  IF p_reason IS NULL OR btrim(p_reason) = '' THEN
    RAISE EXCEPTION 'a correction needs its reason' USING ERRCODE = 'invalid_parameter_value';
  END IF;
  UPDATE class_events SET correct = p_correct, score = p_score WHERE uuid = p_uuid;
  PERFORM at_audit(actor, 'correct', e.class_code, e.user_name || ' ' || p_uuid,
                   json_build_object('correct', e.correct, 'score', e.score)::text,
                   json_build_object('correct', p_correct, 'score', p_score)::text, p_reason);
END
$f$;

-- One outbox event: 'stored', 'repeated' (this sender sent it before) or 'refused: <why>'.
CREATE FUNCTION at_record_event(p_uuid text, p_class text, p_user text, p_kind text, p_occurred bigint,
                                p_lesson text, p_question text, p_structure text, p_correct bigint,
                                p_score double precision, p_payload text)
RETURNS text LANGUAGE plpgsql SECURITY DEFINER AS $f$
DECLARE
  sender text := session_user;
  q_lesson text;
  lesson text := coalesce(p_lesson, '');
  lesson_of_answer text := coalesce(p_lesson, '');
  missing text;
  earlier text;
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
  IF p_kind = 'answer' THEN
    SELECT lesson_id INTO q_lesson FROM questions WHERE id = p_question;
    IF NOT FOUND THEN
      RETURN format('refused: there is no question %s on the class server', coalesce(p_question, 'NULL'));
    END IF;
    IF lesson <> '' AND lesson <> q_lesson THEN
      RETURN format('refused: question %s is not in lesson %s', p_question, lesson);
    END IF;
      IF p_correct IS NULL OR p_correct NOT IN (0, 1) OR p_score IS NULL OR p_score < 0 OR p_score > 1 THEN
      RETURN format('refused: answer %s has an impossible grade', p_uuid);
    END IF;
    lesson := q_lesson;  -- a review answer counts only for a lesson the person may take
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
  IF p_kind = 'lesson_finished' THEN
    SELECT string_agg(s.question_id, ', ' ORDER BY s.position) INTO missing
    FROM steps s
    WHERE s.lesson_id = lesson AND s.kind = 'question' AND NOT EXISTS (
      SELECT 1 FROM class_events e WHERE e.class_code = p_class AND e.user_name = sender AND e.kind = 'answer'
        AND e.lesson_id = lesson AND e.question_id = s.question_id);
    IF missing IS NOT NULL THEN
      RETURN format('refused: %s finished lesson %s without answering %s', sender, lesson, missing);
    END IF;
    IF p_score IS NULL OR p_score < 0 OR p_score > 1 THEN
      RETURN format('refused: lesson end %s has an impossible score', p_uuid);
    END IF;
  END IF;
  INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,
                            correct, score, payload, received_at)
  VALUES (p_uuid, p_class, sender, p_kind, p_occurred, coalesce(p_lesson, ''), coalesce(p_question, ''),
          coalesce(p_structure, ''), p_correct, p_score, coalesce(p_payload, '{}'), extract(epoch FROM now())::bigint);
  RETURN 'stored';
END
$f$;

CREATE FUNCTION at_audit_is_append_only() RETURNS trigger LANGUAGE plpgsql AS $f$
BEGIN
  RAISE EXCEPTION 'class_audit is append-only' USING ERRCODE = 'insufficient_privilege';
END
$f$;
CREATE TRIGGER class_audit_no_update BEFORE UPDATE OR DELETE ON class_audit
  FOR EACH ROW EXECUTE FUNCTION at_audit_is_append_only();
CREATE TRIGGER class_audit_no_truncate BEFORE TRUNCATE ON class_audit
  FOR EACH STATEMENT EXECUTE FUNCTION at_audit_is_append_only();

ALTER TABLE classes ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_members ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_events ENABLE ROW LEVEL SECURITY;
ALTER TABLE class_audit ENABLE ROW LEVEL SECURITY;
CREATE POLICY members_see_their_class ON classes FOR SELECT TO at_class_member
  USING (at_role_in(code) IS NOT NULL);
CREATE POLICY own_or_taught ON class_members FOR SELECT TO at_class_member
  USING (user_name = session_user OR at_role_in(class_code) IN ('instructor', 'coordinator'));
CREATE POLICY own_or_taught ON class_events FOR SELECT TO at_class_member
  USING (user_name = session_user OR at_role_in(class_code) IN ('instructor', 'coordinator'));
CREATE POLICY coordinators_read ON class_audit FOR SELECT TO at_class_member
  USING (at_role_in(class_code) = 'coordinator');

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  EXECUTE format('GRANT USAGE, CREATE ON SCHEMA %I TO at_class_owner', schema_name);
  FOR t IN SELECT tablename FROM pg_tables WHERE schemaname = schema_name LOOP
    EXECUTE format('ALTER TABLE %I.%I OWNER TO at_class_owner', schema_name, t.tablename);
    EXECUTE format('REVOKE ALL ON %I.%I FROM PUBLIC', schema_name, t.tablename);
  END LOOP;
  FOR t IN SELECT p.oid::regprocedure AS fn, p.prosecdef FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname LIKE 'at\_%' LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    IF t.prosecdef THEN EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn); END IF;
  END LOOP;
  EXECUTE format('GRANT USAGE ON SCHEMA %I TO at_class_member', schema_name);
  EXECUTE format('GRANT SELECT ON %I.at_schema_version, %I.classes, %I.class_members, %I.class_events, %I.class_audit'
                 ' TO at_class_member', schema_name, schema_name, schema_name, schema_name, schema_name);
END
$own$;
)SQL";
}

}  // namespace at::db
