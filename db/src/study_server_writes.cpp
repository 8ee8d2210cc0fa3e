#include "study_server_writes.h"

#include <nlohmann/json.hpp>

#include "quiz/study_design.h"
#include "server_refusal.h"

namespace at::db::detail {

namespace {

// Runs `call` (a SELECT of one server function, already bound) to its one row.
Status runCall(Result<Statement>& call) {
  if (!call) return tl::unexpected(call.error());
  auto row = call->step();
  if (!row) return tl::unexpected(serverRefusal(row.error()));
  return {};
}

}  // namespace

bool studyWritesThroughServer(Database& d) {
  if (d.backend() != Backend::Postgres) return false;
  constexpr int kFirstVersionWithStudyFunctions = 21;  // schema.cpp
  auto version = d.schemaVersion();
  return version && *version >= kFirstVersionWithStudyFunctions;
}

Status registerStudyOnServer(Database& d, const quiz::StudyProtocol& protocol, const std::string& owner) {
  auto call = d.prepare("SELECT at_register_study(?1, ?2, ?3, ?4, ?5, ?6)");
  if (call)
    call->bind(1, protocol.id)
        .bind(2, protocol.title)
        .bind(3, protocol.dataset)
        .bind(4, std::int64_t(protocol.seed))
        .bind(5, quiz::serialiseStudyProtocol(protocol))
        .bind(6, owner);
  return runCall(call);
}

Status setStudyOwnerOnServer(Database& d, const std::string& studyId, const std::string& owner) {
  auto call = d.prepare("SELECT at_set_study_owner(?1, ?2)");
  if (call) call->bind(1, studyId).bind(2, owner);
  return runCall(call);
}

Result<int> drawStudyRowOnServer(Database& d, const std::string& studyId) {
  auto call = d.prepare("SELECT at_draw_study_row(?1)");
  if (!call) return tl::unexpected(call.error());
  call->bind(1, studyId);
  auto row = call->step();
  if (!row) return tl::unexpected(serverRefusal(row.error()));
  return call->integer(0);
}

Status enrolOnServer(Database& d, const quiz::StudyProtocol& protocol, const std::string& participantId,
                     const std::string& group, std::optional<int> drawn) {
  nlohmann::json trials = nlohmann::json::array();
  if (drawn)
    for (const quiz::TrialPlan& plan : quiz::planParticipant(protocol.structures.size(), std::size_t(*drawn), protocol.seed)) {
      const std::string& structure = protocol.structures[plan.structureIndex];
      const int a = plan.aIsFirstCondition ? 0 : 1, b = 1 - a;
      trials.push_back({{"position", int(plan.position)},
                        {"structure", structure},
                        {"a_condition", protocol.conditions[std::size_t(a)].id},
                        {"b_condition", protocol.conditions[std::size_t(b)].id},
                        {"preset_a", protocol.presetFor(structure, a)},
                        {"preset_b", protocol.presetFor(structure, b)}});
    }
  auto call = d.prepare("SELECT at_enrol_participant(?1, ?2, ?3, ?4, ?5)");
  if (call) {
    call->bind(1, protocol.id).bind(2, participantId).bind(3, group).bind(5, trials.dump());
    if (drawn) call->bind(4, *drawn);
    else call->bindNull(4);
  }
  return runCall(call);
}

Status recordRatingOnServer(Database& d, const StudyParticipant& participant, const RatingRecord& rating) {
  auto call = d.prepare(
      "SELECT at_record_rating(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15)");
  if (call)
    call->bind(1, participant.studyId)
        .bind(2, participant.participantId)
        .bind(3, participant.session)
        .bind(4, rating.position)
        .bind(5, rating.item)
        .bind(6, rating.ratingAsShown)
        .bind(7, rating.responseMs)
        .bind(8, rating.t)
        .bind(9, rating.alpha)
        .bind(10, rating.beta)
        .bind(11, rating.appVersion)
        .bind(12, rating.qualityLevel)
        .bind(13, rating.qualityFullLevel)
        .bind(14, rating.qualityScale)
        .bind(15, rating.settleMs);
  return runCall(call);
}

Status recordTrialViewingOnServer(Database& d, const StudyParticipant& participant, int position, double viewMsA,
                                  double viewMsB, int toggles, const std::string& comment, bool viewingMeasured) {
  auto call = d.prepare("SELECT at_record_trial_viewing(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
  if (call)
    call->bind(1, participant.studyId)
        .bind(2, participant.participantId)
        .bind(3, participant.session)
        .bind(4, position)
        .bind(5, viewMsA)
        .bind(6, viewMsB)
        .bind(7, toggles)
        .bind(8, comment)
        .bind(9, viewingMeasured ? 1 : 0);
  return runCall(call);
}

Status completeParticipantOnServer(Database& d, const StudyParticipant& participant) {
  auto call = d.prepare("SELECT at_complete_participant(?1, ?2, ?3)");
  if (call) call->bind(1, participant.studyId).bind(2, participant.participantId).bind(3, participant.session);
  return runCall(call);
}

}  // namespace at::db::detail
