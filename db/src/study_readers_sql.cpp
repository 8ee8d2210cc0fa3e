// Who reads a study on a class server, PostgreSQL only (after study_security_sql.cpp and
// study_checks_sql.cpp):
//
//  - a study, its participants, their blinded trials (the A/B keys), their ratings and the study's
//    withdrawals in class_audit are read by the study's owner only while that login is a class's
//    coordinator now (class_members: role coordinator, not withdrawn), as study writes already
//    require (at_require_current_coordinator). A coordinator demoted or withdrawn in every class
//    reads none of it any more, her own studies included; promoted again, she reads them again.
//    Role changes and withdrawals are audited where they happen (class_audit).
//  - the administrator (no class login) is not limited.
#include "study_readers_sql.h"

namespace at::db {

std::string_view studyReadersSql() {
  return R"SQL(
-- True when this connection's login owns study p_study and coordinates a class now.
CREATE OR REPLACE FUNCTION at_owns_study(p_study text) RETURNS boolean LANGUAGE sql STABLE SECURITY DEFINER AS $f$
  SELECT EXISTS (SELECT 1 FROM studies WHERE id = p_study AND owner = session_user AND owner <> '')
     AND EXISTS (SELECT 1 FROM class_members WHERE user_name = session_user AND role = 'coordinator'
                 AND withdrawn_at IS NULL)
$f$;

DROP POLICY owner_reads ON studies;
CREATE POLICY owner_reads ON studies FOR SELECT TO at_class_member USING (at_owns_study(id));

DO $own$
DECLARE
  schema_name text := current_schema();
  t record;
BEGIN
  FOR t IN SELECT p.oid::regprocedure AS fn FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
           WHERE n.nspname = schema_name AND p.proname = 'at_owns_study' LOOP
    EXECUTE format('ALTER FUNCTION %s OWNER TO at_class_owner', t.fn);
    EXECUTE format('ALTER FUNCTION %s SET search_path = %I, pg_temp', t.fn, schema_name);
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', t.fn);
    EXECUTE format('GRANT EXECUTE ON FUNCTION %s TO at_class_member', t.fn);
  END LOOP;
END
$own$;
)SQL";
}

}  // namespace at::db
