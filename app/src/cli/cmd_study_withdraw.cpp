// `anatomy-tutor study withdraw STUDY PARTICIPANT --reason TEXT [--exclude]`: a study's coordinator
// withdraws a participant who withdrew consent, or excludes one (db/study_withdrawal.h). Their rows
// stay, with the reason; exports and Table 2 leave them out; `study status` and the export's
// withdrawals.csv list them; the change is audited.
#include "cli_args.h"
#include "commands.h"
#include "db/class_accounts.h"
#include "db/connection.h"
#include "db/study_withdrawal.h"
#include "printable_output.h"

namespace at::app {

int runStudyWithdraw(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("study withdraw: give STUDY PARTICIPANT");
  const auto reason = args.value("reason");
  if (!reason || reason->find_first_not_of(" \t") == std::string::npos)
    return reportError("study withdraw: --reason TEXT is required (it is kept with the participant and in the audit)");
  auto database = db::openDatabase(args.db());
  if (!database) return reportError("study withdraw: " + database.error().message);
  std::optional<std::string> by = args.user();
  if (database->backend() == db::Backend::Postgres) {
    auto acting = db::actingName(*database, args.user());
    if (acting) by = *acting;
    else if (args.user()) return reportError("study withdraw: " + acting.error().message);
  }
  const auto kind = args.has("exclude") ? db::StudyWithdrawalKind::Excluded : db::StudyWithdrawalKind::Withdrawn;
  const std::string& study = args.positional()[0];
  const std::string& participant = args.positional()[1];
  if (auto done = db::withdrawStudyParticipant(*database, study, participant, kind, *reason, by); !done)
    return reportError("study withdraw: " + done.error().message);
  terminalPrintf("participant %s of study %s is %s (%s); their ratings stay stored but leave every export and the "
                 "summary from now on\n",
                 participant.c_str(), study.c_str(), db::toString(kind), reason->c_str());
  return 0;
}

}  // namespace at::app
