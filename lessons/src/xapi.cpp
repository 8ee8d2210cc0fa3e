#include "lessons/xapi.h"

#include <cstdio>
#include <ctime>

#include <nlohmann/json.hpp>

#include "core/name_uuid.h"

namespace at::lessons {

namespace {

using json = nlohmann::json;

constexpr const char* kInteraction = "http://adlnet.gov/expapi/activities/cmi.interaction";

json verb(const char* name) {
  return {{"id", std::string("http://adlnet.gov/expapi/verbs/") + name}, {"display", {{"en-US", name}}}};
}

// Percent-encodes everything but RFC 3986's unreserved characters (an id as one path segment).
std::string pathSegment(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out += char(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

std::string isoTime(std::int64_t unixSeconds) {
  const std::time_t t = std::time_t(unixSeconds);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

// ISO 8601 duration of `ms` milliseconds ("PT1.25S").
std::string duration(double ms) {
  char text[48];
  std::snprintf(text, sizeof text, "PT%.2fS", std::max(0.0, ms) / 1000.0);
  return text;
}

json actor(const std::string& name, const XapiOptions& o) {
  return {{"objectType", "Agent"}, {"name", name}, {"account", {{"homePage", o.homePage}, {"name", name}}}};
}

json activity(const std::string& id, json definition) {
  return {{"objectType", "Activity"}, {"id", id}, {"definition", std::move(definition)}};
}

json context(const XapiOptions& o, json extensions = json::object()) {
  json c = {{"platform", "Anatomy Tutor"}, {"language", "en"}};
  if (!o.appVersion.empty()) extensions[o.activityBase + "/extensions/app-version"] = o.appVersion;
  if (!extensions.empty()) c["extensions"] = std::move(extensions);
  return c;
}

// An answer as an interaction: its type, the response in xAPI's format for that type and, for
// choice and sequencing, the choices offered and the correct response pattern.
struct Interaction {
  const char* type = "other";
  std::string response;
  json choices;   // null: none
  json correct;   // null: none
};

std::string joinedIds(const std::vector<std::string>& ids) {
  std::string joined;
  for (const std::string& s : ids) joined += (joined.empty() ? "" : "[,]") + s;
  return joined;
}

json choiceList(const std::vector<std::string>& ids, const XapiQuestion& q) {
  json list = json::array();
  for (const std::string& id : ids) {
    const auto name = q.names.find(id);
    list.push_back({{"id", id}, {"description", {{"en-US", name != q.names.end() ? name->second : id}}}});
  }
  return list;
}

// An ordered item as its choice id: the id itself, else the structure whose shown name it is
// (answers may give names), else as given.
std::string choiceIdOf(const std::string& item, const XapiQuestion& q) {
  for (const std::string& id : q.resolved.choices)
    if (id == item) return id;
  for (const auto& [id, name] : q.names)
    if (name == item) return id;
  return item;
}

Interaction interactionOf(const quiz::Answer& a, const XapiQuestion* q) {
  Interaction out;
  if (a.choice) {
    const auto& offered = q ? q->resolved.choices : std::vector<std::string>{};
    if (*a.choice < 0 || std::size_t(*a.choice) >= offered.size()) {
      out.response = std::to_string(*a.choice);  // choices not known: no choice interaction
      return out;
    }
    out.type = "choice";
    out.response = offered[std::size_t(*a.choice)];
    out.choices = choiceList(offered, *q);
    if (q->resolved.keyChoice >= 0 && std::size_t(q->resolved.keyChoice) < offered.size())
      out.correct = json::array({offered[std::size_t(q->resolved.keyChoice)]});
    return out;
  }
  if (a.text) {
    out.type = "fill-in";
    out.response = *a.text;
    return out;
  }
  if (a.order) {
    if (!q || q->resolved.choices.empty()) {
      out.response = joinedIds(*a.order);
      return out;
    }
    std::vector<std::string> ids;
    for (const std::string& item : *a.order) ids.push_back(choiceIdOf(item, *q));
    out.type = "sequencing";
    out.response = joinedIds(ids);
    out.choices = choiceList(q->resolved.choices, *q);
    if (!q->resolved.keyOrder.empty()) out.correct = json::array({joinedIds(q->resolved.keyOrder)});
    return out;
  }
  if (a.pick && a.pick->pixel)  // graded on a class server from the pixel clicked on the item's picture
    out.response = "pixel " + std::to_string((*a.pick->pixel)[0]) + " " + std::to_string((*a.pick->pixel)[1]);
  else if (a.pick) out.response = a.pick->structure.empty() ? std::string("nothing") : a.pick->structure;
  return out;
}

// `parentId`: the activity the question was asked in (a lesson, an exam; empty: none).
json answered(const User& user, const GradedAnswer& g, const std::string& parentId, const std::string& key,
              const XapiOptions& o, const XapiQuestion* question) {
  const Interaction interaction = interactionOf(g.answer, question);
  json definition = {{"type", kInteraction}, {"interactionType", interaction.type}, {"name", {{"en-US", g.questionId}}}};
  if (!interaction.choices.is_null()) definition["choices"] = interaction.choices;
  if (!interaction.correct.is_null()) definition["correctResponsesPattern"] = interaction.correct;
  json extensions = {{o.activityBase + "/extensions/structure", g.structureId},
                     {o.activityBase + "/extensions/render",
                      {{"preset", g.render.presetId}, {"mode", g.render.mode}, {"t", g.render.t},
                       {"alpha", g.render.alpha}, {"beta", g.render.beta}}}};
  if (g.answer.pick && g.answer.pick->distanceMm >= 0)
    extensions[o.activityBase + "/extensions/pick-distance-mm"] = g.answer.pick->distanceMm;
  json ctx = context(o, std::move(extensions));
  if (!parentId.empty())
    ctx["contextActivities"] = {{"parent", json::array({{{"objectType", "Activity"}, {"id", parentId}}})}};
  json result = {{"success", g.correct},
                 {"score", {{"scaled", g.score}, {"raw", g.score}, {"min", 0}, {"max", 1}}},
                 {"response", interaction.response}};
  if (g.latencyMs > 0) result["duration"] = duration(double(g.latencyMs));
  return {{"id", nameBasedUuid(key)},
          {"actor", actor(user.name, o)},
          {"verb", verb("answered")},
          {"object", activity(o.activityBase + "/questions/" + pathSegment(g.questionId), std::move(definition))},
          {"result", std::move(result)},
          {"context", std::move(ctx)},
          {"timestamp", isoTime(g.answeredAt)}};
}

const XapiQuestion* questionOf(const XapiQuestions& questions, const std::string& id) {
  const auto found = questions.find(id);
  return found != questions.end() ? &found->second : nullptr;
}

std::string lessonId(const std::string& lesson, const XapiOptions& o) {
  return o.activityBase + "/lessons/" + pathSegment(lesson);
}

json lessonActivity(const std::string& lessonId, const XapiOptions& o) {
  return activity(o.activityBase + "/lessons/" + pathSegment(lessonId),
                  {{"type", "http://adlnet.gov/expapi/activities/lesson"}, {"name", {{"en-US", lessonId}}}});
}

// An exam attempt: attempted, each answered item (a question carrying its own choices and keys),
// completed with the score and, when the exam has a pass mark, success.
void examStatements(const User& user, const ExamRecord& e, const std::string& who, const XapiOptions& o, json& out) {
  const ExamAttempt& a = e.attempt;
  const std::string examId = o.activityBase + "/exams/" + pathSegment(a.examId);
  const json exam = activity(examId, {{"type", "http://adlnet.gov/expapi/activities/assessment"},
                                      {"name", {{"en-US", a.examId}}}});
  const std::string attemptKey = who + "exam|" + a.examId + "|" + std::to_string(a.startedAt) + "|" + std::to_string(a.id);
  out.push_back({{"id", nameBasedUuid(attemptKey + "|attempted")},
                 {"actor", actor(user.name, o)},
                 {"verb", verb("attempted")},
                 {"object", exam},
                 {"context", context(o, {{o.activityBase + "/extensions/course", a.courseId}})},
                 {"timestamp", isoTime(a.startedAt)}});
  for (const ExamItem& item : e.items) {
    if (!item.answer) continue;
    GradedAnswer g;
    g.questionId = item.question.question.id;
    g.structureId = item.question.question.target;
    g.answer = *item.answer;
    g.correct = item.correct;
    g.score = item.score;
    g.latencyMs = item.latencyMs;
    g.answeredAt = item.answeredAt;
    const XapiQuestion asked{item.question, {}};
    out.push_back(answered(user, g, examId, attemptKey + "|item|" + std::to_string(item.position), o, &asked));
  }
  if (a.finishedAt) {
    json result = {{"completion", true},
                   {"score", {{"scaled", a.score}, {"raw", a.score}, {"min", 0}, {"max", 1}}},
                   {"duration", duration(1000.0 * double(*a.finishedAt - a.startedAt))}};
    if (a.passed) result["success"] = *a.passed;
    out.push_back({{"id", nameBasedUuid(attemptKey + "|completed")},
                   {"actor", actor(user.name, o)},
                   {"verb", verb("completed")},
                   {"object", exam},
                   {"result", std::move(result)},
                   {"context", context(o, {{o.activityBase + "/extensions/course", a.courseId}})},
                   {"timestamp", isoTime(*a.finishedAt)}});
  }
}

void learnerStatements(const LearnerRecords& r, const XapiOptions& o, const XapiQuestions& questions, json& out) {
  const std::string who = "user|" + o.homePage + "|" + r.user.name + "|";
  for (const Attempt& a : r.attempts) {
    const std::string attemptKey = who + "attempt|" + a.lessonId + "|" + std::to_string(a.startedAt) + "|" + std::to_string(a.id);
    out.push_back({{"id", nameBasedUuid(attemptKey + "|attempted")},
                   {"actor", actor(r.user.name, o)},
                   {"verb", verb("attempted")},
                   {"object", lessonActivity(a.lessonId, o)},
                   {"context", context(o, {{o.activityBase + "/extensions/mode", toString(a.mode)}})},
                   {"timestamp", isoTime(a.startedAt)}});
    if (auto found = r.responses.find(a.id); found != r.responses.end())
      for (const Response& x : found->second)
        out.push_back(answered(r.user, x, lessonId(a.lessonId, o), attemptKey + "|step|" + std::to_string(x.stepIndex), o,
                               questionOf(questions, x.questionId)));
    if (a.finishedAt) {
      json result = {{"completion", true},
                     {"score", {{"scaled", a.score}, {"raw", a.score}, {"min", 0}, {"max", 1}}},
                     {"duration", duration(1000.0 * double(*a.finishedAt - a.startedAt))}};
      out.push_back({{"id", nameBasedUuid(attemptKey + "|completed")},
                     {"actor", actor(r.user.name, o)},
                     {"verb", verb("completed")},
                     {"object", lessonActivity(a.lessonId, o)},
                     {"result", std::move(result)},
                     {"context", context(o)},
                     {"timestamp", isoTime(*a.finishedAt)}});
    }
  }
  for (const ReviewResponse& x : r.reviews)
    out.push_back(answered(r.user, x, "",
                           who + "review|" + x.questionId + "|" + std::to_string(x.answeredAt) + "|" + std::to_string(x.id),
                           o, questionOf(questions, x.questionId)));
  for (const ExamRecord& e : r.exams) examStatements(r.user, e, who, o, out);
}

void ratingStatements(const StudyRatings& s, const XapiOptions& o, json& out) {
  const quiz::StudyProtocol& p = s.protocol;
  json scale = json::array();
  for (int v = p.scale.min; v <= p.scale.max; ++v) {
    const auto anchor = p.scale.anchors.find(v);
    scale.push_back({{"id", std::to_string(v)},
                     {"description", {{"en-US", anchor != p.scale.anchors.end() ? anchor->second : std::to_string(v)}}}});
  }
  const std::string studyBase = o.activityBase + "/studies/" + pathSegment(p.id);
  for (const quiz::StudyResponseRow& r : s.rows) {
    std::string wording = r.item;
    for (const quiz::StudyItem& item : p.items)
      if (item.id == r.item) wording = item.wording;
    json definition = {{"type", kInteraction},
                       {"interactionType", "likert"},
                       {"name", {{"en-US", r.structure + ": " + r.item}}},
                       {"description", {{"en-US", wording}}},
                       {"scale", scale}};
    json result = {{"response", std::to_string(r.ratingAb)}};
    if (r.responseMs > 0) result["duration"] = duration(r.responseMs);
    json extensions = {{o.activityBase + "/extensions/condition-shown-as-a", r.aCondition},
                       {o.activityBase + "/extensions/rating-unblinded", r.rating},
                       {o.activityBase + "/extensions/group", r.group},
                       {o.activityBase + "/extensions/session", r.session}};
    // Viewing times only where they were measured: absent, never 0, for views shown as files.
    if (r.viewingMeasured) {
      extensions[o.activityBase + "/extensions/view-ms-a"] = r.viewMsA;
      extensions[o.activityBase + "/extensions/view-ms-b"] = r.viewMsB;
    }
    json ctx = context(o, std::move(extensions));
    ctx["registration"] = nameBasedUuid("study|" + o.homePage + "|" + p.id + "|" + r.participantId);
    ctx["contextActivities"] = {{"parent", json::array({{{"objectType", "Activity"}, {"id", studyBase}}})}};
    json statement = {
        {"id", nameBasedUuid("rating|" + o.homePage + "|" + p.id + "|" + r.participantId + "|" + r.structure + "|" + r.item)},
        {"actor", actor(r.participantId, o)},
        {"verb", verb("answered")},
        {"object", activity(studyBase + "/" + pathSegment(r.structure) + "/" + pathSegment(r.item), std::move(definition))},
        {"result", std::move(result)},
        {"context", std::move(ctx)}};
    if (!r.timestampUtc.empty()) statement["timestamp"] = r.timestampUtc;
    out.push_back(std::move(statement));
  }
}

bool httpUrl(const std::string& text) {
  for (const char* scheme : {"http://", "https://"})
    if (text.rfind(scheme, 0) == 0 && text.size() > std::string(scheme).size()) return true;
  return false;
}

}  // namespace

Status checkXapiOptions(const XapiOptions& o) {
  if (!httpUrl(o.homePage)) return fail("xAPI home page '" + o.homePage + "' is not an http:// or https:// URL");
  if (!httpUrl(o.activityBase)) return fail("xAPI activity base '" + o.activityBase + "' is not an http:// or https:// URL");
  return {};
}

std::string xapiStatementsJson(const std::vector<LearnerRecords>& learners, const std::vector<StudyRatings>& studies,
                               const XapiOptions& options, const XapiQuestions& questions) {
  json out = json::array();
  for (const LearnerRecords& r : learners) learnerStatements(r, options, questions, out);
  for (const StudyRatings& s : studies) ratingStatements(s, options, out);
  return out.dump(2);
}

std::string nameBasedUuid(std::string_view name) { return *uuidV5(kUrlNamespaceUuid, name); }

}  // namespace at::lessons
