#include "lessons/xapi.h"

#include <cstdio>
#include <ctime>

#include <nlohmann/json.hpp>

#include "core/sha256.h"

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

// The interaction type and the response (xAPI's response formats) of an answer as given.
std::pair<const char*, std::string> interactionOf(const quiz::Answer& a) {
  if (a.choice) return {"choice", std::to_string(*a.choice)};
  if (a.text) return {"fill-in", *a.text};
  if (a.order) {
    std::string joined;
    for (const std::string& s : *a.order) joined += (joined.empty() ? "" : "[,]") + s;
    return {"sequencing", joined};
  }
  if (a.pick) return {"other", a.pick->structure.empty() ? std::string("nothing") : a.pick->structure};
  return {"other", ""};
}

json answered(const User& user, const GradedAnswer& g, const std::string& lessonId, const std::string& key,
              const XapiOptions& o) {
  const auto [type, response] = interactionOf(g.answer);
  json definition = {{"type", kInteraction}, {"interactionType", type}, {"name", {{"en-US", g.questionId}}}};
  json extensions = {{o.activityBase + "/extensions/structure", g.structureId},
                     {o.activityBase + "/extensions/render",
                      {{"preset", g.render.presetId}, {"mode", g.render.mode}, {"t", g.render.t},
                       {"alpha", g.render.alpha}, {"beta", g.render.beta}}}};
  if (g.answer.pick && g.answer.pick->distanceMm >= 0)
    extensions[o.activityBase + "/extensions/pick-distance-mm"] = g.answer.pick->distanceMm;
  json ctx = context(o, std::move(extensions));
  if (!lessonId.empty())
    ctx["contextActivities"] = {{"parent", json::array({{{"objectType", "Activity"},
                                                          {"id", o.activityBase + "/lessons/" + pathSegment(lessonId)}}})}};
  json result = {{"success", g.correct},
                 {"score", {{"scaled", g.score}, {"raw", g.score}, {"min", 0}, {"max", 1}}},
                 {"response", response}};
  if (g.latencyMs > 0) result["duration"] = duration(double(g.latencyMs));
  return {{"id", nameBasedUuid(key)},
          {"actor", actor(user.name, o)},
          {"verb", verb("answered")},
          {"object", activity(o.activityBase + "/questions/" + pathSegment(g.questionId), std::move(definition))},
          {"result", std::move(result)},
          {"context", std::move(ctx)},
          {"timestamp", isoTime(g.answeredAt)}};
}

json lessonActivity(const std::string& lessonId, const XapiOptions& o) {
  return activity(o.activityBase + "/lessons/" + pathSegment(lessonId),
                  {{"type", "http://adlnet.gov/expapi/activities/lesson"}, {"name", {{"en-US", lessonId}}}});
}

void learnerStatements(const LearnerRecords& r, const XapiOptions& o, json& out) {
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
        out.push_back(answered(r.user, x, a.lessonId, attemptKey + "|step|" + std::to_string(x.stepIndex), o));
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
                           o));
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
                               const XapiOptions& options) {
  json out = json::array();
  for (const LearnerRecords& r : learners) learnerStatements(r, options, out);
  for (const StudyRatings& s : studies) ratingStatements(s, options, out);
  return out.dump(2);
}

std::string nameBasedUuid(std::string_view name) {
  Sha256 hash;
  hash.update(name);
  std::string hex = hash.hex().substr(0, 32);
  hex[12] = '8';                                                   // version 8
  hex[16] = "89ab"[std::stoi(hex.substr(16, 1), nullptr, 16) & 3];  // variant 10xx
  return hex.substr(0, 8) + "-" + hex.substr(8, 4) + "-" + hex.substr(12, 4) + "-" + hex.substr(16, 4) + "-" +
         hex.substr(20, 12);
}

}  // namespace at::lessons
