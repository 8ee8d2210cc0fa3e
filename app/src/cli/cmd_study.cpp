// `anatomy-tutor study …`: preference studies in the terminal (the paper's survey design).
//   study register FILE.json                   store (or update) a study definition
//   study list                                 studies in the database
//   study run STUDY --participant ID --group G --answers FILE.jsonl
//   study status STUDY                         participants and their completion
//   study export STUDY --out DIR               the coordinator's files (CSV, JSON, Markdown, SVG, PNG)
//   study merge STUDY SOURCE...                 participants of other machines' databases or export
//                                               folders into --db
// STUDY is a stored study id, a shipped study id (data/studies/<file>.json, registered on first
// use) or a path to a study JSON file.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_args.h"
#include "commands.h"
#include "db/connection.h"
#include "dataset_resolver.h"
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_report.h"
#include "render/preset.h"
#include "study_session.h"
#include "printable_output.h"

namespace at::app {

namespace {

namespace fs = std::filesystem;

const char* kStudyHelp =
    "usage: anatomy-tutor study register FILE.json [--db PATH]\n"
    "       anatomy-tutor study list [--db PATH]\n"
    "       anatomy-tutor study run STUDY --participant ID --group G --answers FILE.jsonl [--db PATH]\n"
    "       anatomy-tutor study status STUDY [--db PATH]\n"
    "       anatomy-tutor study export STUDY --out DIR [--db PATH]\n"
    "       anatomy-tutor study merge STUDY SOURCE... [--db PATH]   (SOURCE: a database or an export folder)\n"
    "       anatomy-tutor study withdraw STUDY PARTICIPANT --reason TEXT [--exclude] [--db PATH]\n"
    "register --owner LOGIN: on a class server, the coordinator's login that alone reads the study\n"
    "  (status, export) and withdraws its participants.\n"
    "withdraw: the participant withdrew consent (or, with --exclude, is excluded); their rows stay,\n"
    "  with the reason, but leave every export and the summary; status and the export's\n"
    "  withdrawals.csv list them, and the change is audited.\n"
    "\n"
    "Preference studies comparing the WDT rendering with the bare-structure rendering of each\n"
    "structure, blinded as A and B with counterbalanced order (the paper's Table 2 design).\n"
    "STUDY: a stored study id, a shipped study (data/studies) or a study JSON file.\n"
    "run --answers: one JSON line per structure, naming the structure by its number as presented:\n"
    "  {\"trial\": 1, \"ratings\": {\"shape\": 2, \"context\": 1, …}, \"view_ms_a\": 4000, \"view_ms_b\": 3500,\n"
    "   \"toggles\": 3, \"comment\": \"…\", \"response_ms\": 1200}   (ratings as shown: 1 = prefer A … 5 = prefer B)\n"
    "  Running again (after a stop or a server drop) with the same file records only the structures\n"
    "  not yet rated, each from the line naming it. Lines without \"trial\" are taken in order, and\n"
    "  only for a participant with no ratings yet: a resumed file must name its trials.\n"
    "Participants run in the desktop app (Studies…): the terminal cannot show the two renderings.\n"
    "Here --answers records answers collected elsewhere (required).\n"
    "merge: copies every participant of STUDY from the SOURCE databases (lab machines' files or\n"
    "  servers) or export folders (what 'study export --out' wrote: its responses_long.csv is read\n"
    "  back) into --db, all or nothing: the same id with other records is refused, merging again\n"
    "  changes nothing. It reports how the machines' counterbalancing rows add up; export the merged\n"
    "  study for the recomputed summary.\n";

Result<db::Connection> openDb(const cli::Args& args) { return db::openDatabase(args.db()); }

// For the verbs that only read (list, status, export): a database that cannot be written is read.
Result<db::Connection> openDbToRead(const cli::Args& args) {
  db::OpenOptions options;
  options.readOnlyIfNotWritable = true;
  return db::openDatabase(args.db(), options);
}

int runRegister(const cli::Args& args) {
  if (args.positional().size() != 1) return reportError("study register: expected one study JSON file");
  auto protocol = quiz::loadStudyProtocol(args.positional()[0]);
  if (!protocol) return reportError(protocol.error().message);
  auto database = openDb(args);
  if (!database) return reportError(database.error().message);
  if (auto s = db::saveStudy(*database, *protocol); !s) return reportError(s.error().message);
  if (const auto owner = args.value("owner"))
    if (auto s = db::setStudyOwner(*database, protocol->id, *owner); !s) return reportError(s.error().message);
  terminalPrintf("stored study '%s' (%zu structures, %zu items, groups:", protocol->id.c_str(),
              protocol->structures.size(), protocol->items.size());
  for (const auto& g : protocol->groups) terminalPrintf(" %s", g.c_str());
  terminalPrintf(")\n");
  return 0;
}

int runList(const cli::Args& args) {
  auto database = openDbToRead(args);
  if (!database) return reportError(database.error().message);
  auto studies = db::listStudies(*database);
  if (!studies) return reportError(studies.error().message);
  for (const auto& s : *studies) {
    auto completion = db::studyCompletion(*database, s.id);
    std::size_t done = 0, total = completion ? completion->size() : 0;
    if (completion)
      for (const auto& c : *completion) done += c.complete ? 1 : 0;
    terminalPrintf("%-28s %zu/%zu participants complete  %s\n", rowCell(s.id).c_str(), done, total, rowCell(s.title).c_str());
  }
  return 0;
}

int runStatus(const cli::Args& args) {
  if (args.positional().size() != 1) return reportError("study status: expected STUDY");
  auto database = openDbToRead(args);
  if (!database) return reportError(database.error().message);
  auto protocol = resolveStudy(*database, args.positional()[0]);
  if (!protocol) return reportError(protocol.error().message);
  auto completion = db::studyCompletion(*database, protocol->id);
  if (!completion) return reportError(completion.error().message);
  terminalPrintf("study %s: %zu participant(s)\n", protocol->id.c_str(), completion->size());
  for (const auto& c : *completion)
    terminalPrintf("  %-20s %-14s %3d/%d ratings  %s\n", c.participantId.c_str(), c.group.c_str(), c.ratingsGiven,
                c.ratingsExpected, c.withdrawal ? c.withdrawal->c_str() : c.complete ? "complete" : "in progress");
  return 0;
}

struct TrialAnswer {
  std::optional<int> trial;            // 1-based presentation number the line names, if it names one
  std::map<std::string, int> ratings;  // item → rating as shown
  double viewMsA = 0, viewMsB = 0, responseMs = 0;
  int toggles = 0;
  std::string comment;
};

// Reads one answers line strictly; errors name the line number and the field.
Result<TrialAnswer> parseAnswerLine(const std::string& line, int lineNumber, const std::string& file,
                                    const quiz::StudyProtocol& protocol, std::size_t trialCount) {
  const std::string where = file + ":" + std::to_string(lineNumber);
  nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return fail(where + ": not a JSON object");
  TrialAnswer a;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (key == "ratings") {
      if (!it->is_object()) return fail(where + ": 'ratings' must be an object of item → rating");
      for (auto r = it->begin(); r != it->end(); ++r) {
        bool known = false;
        for (const auto& item : protocol.items) known = known || item.id == r.key();
        if (!known) return fail(where + ": 'ratings." + r.key() + "' is not an item of study '" + protocol.id + "'");
        if (!r->is_number_integer() || r->get<int>() < protocol.scale.min || r->get<int>() > protocol.scale.max)
          return fail(where + ": 'ratings." + r.key() + "' must be an integer " + std::to_string(protocol.scale.min) +
                      ".." + std::to_string(protocol.scale.max));
        a.ratings[r.key()] = r->get<int>();
      }
    } else if (key == "view_ms_a" || key == "view_ms_b" || key == "response_ms") {
      if (!it->is_number() || it->get<double>() < 0) return fail(where + ": '" + key + "' must be a number ≥ 0");
      (key == "view_ms_a" ? a.viewMsA : key == "view_ms_b" ? a.viewMsB : a.responseMs) = it->get<double>();
    } else if (key == "trial") {
      if (!it->is_number_integer() || it->get<long long>() < 1 || it->get<long long>() > (long long)trialCount)
        return fail(where + ": 'trial' must be the structure's number as presented, an integer 1.." +
                    std::to_string(trialCount));
      a.trial = it->get<int>();
    } else if (key == "toggles") {
      if (!it->is_number_integer() || it->get<int>() < 0) return fail(where + ": 'toggles' must be an integer ≥ 0");
      a.toggles = it->get<int>();
    } else if (key == "comment") {
      if (!it->is_string()) return fail(where + ": 'comment' must be a string");
      a.comment = it->get<std::string>();
    } else {
      return fail(where + ": unknown field '" + key + "'");
    }
  }
  if (a.ratings.size() != protocol.items.size())
    return fail(where + ": 'ratings' must rate every item (" + std::to_string(protocol.items.size()) + "), got " +
                std::to_string(a.ratings.size()));
  return a;
}

// Records the answers file's lines into the participant's trials. A line naming its trial
// ("trial": N, the structure's number as presented) is that trial's answer, whatever its place in
// the file; a trial already fully rated is left as recorded, so running again with the same file
// after a stop or a server drop records only what is missing. Lines naming no trial are taken in
// presentation order, which is only sound for a participant with no ratings yet: for one being
// resumed such a file is refused before anything is written (else its first line would land on the
// first structure not yet rated). Each rating is committed before the next is taken.
Status recordAnswers(db::Database& database, const quiz::StudyProtocol& protocol,
                     const std::map<std::string, render::Preset>& presets, db::StudyParticipant& state,
                     std::istream& answersFile, const std::string& answersPath) {
  const std::size_t itemCount = protocol.items.size(), trialCount = state.trials.size();
  std::size_t alreadyRated = 0;
  for (const auto& trial : state.trials) alreadyRated += trial.ratedItems.size();
  std::set<int> named;            // trials named by lines read so far
  std::size_t unnamedLines = 0;   // lines naming no trial, read so far
  int lineNumber = 0;
  std::string line;
  while (std::getline(answersFile, line)) {
    ++lineNumber;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = answersPath + ":" + std::to_string(lineNumber);
    auto answer = parseAnswerLine(line, lineNumber, answersPath, protocol, trialCount);
    if (!answer) return tl::unexpected(answer.error());
    std::size_t index = 0;
    if (answer->trial) {
      if (unnamedLines > 0)
        return fail(where + ": names a trial but earlier lines do not: name the trial (\"trial\": N) on every line");
      if (!named.insert(*answer->trial).second)
        return fail(where + ": trial " + std::to_string(*answer->trial) + " is answered twice in the file");
      index = std::size_t(*answer->trial - 1);
    } else {
      if (!named.empty())
        return fail(where + ": names no trial but earlier lines do: name the trial (\"trial\": N) on every line");
      if (alreadyRated > 0)
        return fail(ErrorKind::Conflict,
                    where + ": participant " + state.participantId + " already has " + std::to_string(alreadyRated) +
                        " rating(s), so this run resumes: each answers line must name its structure (\"trial\": N, "
                        "its number as presented) or the answers would land on other structures; nothing was recorded");
      if (unnamedLines >= trialCount)
        return fail(where + ": more answer lines than the study's " + std::to_string(trialCount) + " structures");
      index = unnamedLines++;
    }
    db::StudyTrial& trial = state.trials[index];
    // Blinded: the structure and the conditions are not named to the participant.
    terminalPrintf("\nStructure %d of %zu\n", trial.position + 1, trialCount);
    if (trial.ratedItems.size() >= itemCount) {
      terminalPrintf("  already rated: kept as recorded\n");
      continue;
    }
    for (const auto& item : protocol.items) {
      if (trial.ratedItems.count(item.id)) continue;
      const db::RatingRecord r = makeRating(protocol, presets.at(protocol.presetFor(trial.structure, 0)),
                                            trial.position, item.id, answer->ratings.at(item.id), answer->responseMs);
      if (auto s = db::recordRating(database, state, r); !s) return s;
      trial.ratedItems.insert(item.id);
      terminalPrintf("  %s: %d recorded\n", item.id.c_str(), r.ratingAsShown);
    }
    if (auto s = db::recordTrialViewing(database, state, trial.position, answer->viewMsA, answer->viewMsB,
                                        answer->toggles, answer->comment);
        !s)
      return s;
  }
  return {};
}

int runRun(const cli::Args& args) {
  if (args.positional().size() != 1) return reportError("study run: expected STUDY (see --help)");
  const auto participant = args.value("participant");
  const auto group = args.value("group");
  if (!participant || participant->empty()) return reportError("study run: --participant ID is required");
  if (!group) return reportError("study run: --group G is required");
  // A participant must see the two renderings to rate them; the terminal cannot show them, and
  // viewing times of images nobody saw would be made up.
  if (!args.has("answers"))
    return reportError("study run: the terminal cannot show the renderings A and B: run participants in the desktop "
                       "app (Studies…), or give --answers FILE.jsonl with answers collected elsewhere");
  const std::string answersPath = args.valueOr("answers", "");
  // A stream by design (answers piped in as a participant gives them, /dev/stdin): not refused as a FIFO.
  std::ifstream answersFile(answersPath);
  if (!answersFile) return reportError(answersPath + ": cannot open the answers file");
  auto database = openDb(args);
  if (!database) return reportError(database.error().message);
  auto protocol = resolveStudy(*database, args.positional()[0]);
  if (!protocol) return reportError(protocol.error().message);
  // Both presets of every structure must exist (written, or derived from the study's dataset)
  // before anyone is enrolled; the WDT preset's α and β are recorded with each rating (the render
  // parameters on screen).
  const StudyLevels levels = [&]() -> Result<render::IntensityLevels> {
    DatasetRequest request;
    request.name = protocol->dataset;
    request.database = &database->get();
    auto dataset = openNamedDataset(request);
    if (!dataset) return tl::unexpected(dataset.error());
    for (const std::string& structure : protocol->structures)
      if (!dataset->findStructure(structure))
        return fail(ErrorKind::NotFound, "structure '" + structure + "': " + unknownStructureMessage(*dataset, structure));
    return render::summariseIntensities(dataset->volume);
  };
  auto presets = loadStudyPresets(render::PresetLibrary(defaultPresetsDir()), *protocol, levels);
  if (!presets) return reportError(presets.error().message);
  auto state = db::enrolOrResume(*database, *protocol, *participant, *group);
  if (!state) return reportError(state.error().message);

  // Participants see neither the study's id nor its title: both may name the conditions.
  terminalPrintf("Preference study — participant %s (%s), session %d\n", participant->c_str(), group->c_str(),
              state->session);
  terminalPrintf("For each of %zu structures you will see two renderings, A and B. Rate each item from %d (prefer A) "
              "to %d (prefer B).\n",
              protocol->structures.size(), protocol->scale.min, protocol->scale.max);
  if (auto s = recordAnswers(*database, *protocol, *presets, *state, answersFile, answersPath); !s)
    return reportError(s.error().message);
  if (!state->nextTrial(protocol->items.size())) {
    if (auto s = db::markParticipantComplete(*database, *state); !s)
      return reportError(s.error().message);
    terminalPrintf("\nThank you: all %zu structures rated.\n", state->trials.size());
  } else {
    terminalPrintf("\nStopped before the end (structures not rated:");
    for (const auto& trial : state->trials)
      if (trial.ratedItems.size() < protocol->items.size()) terminalPrintf(" %d", trial.position + 1);
    terminalPrintf("); run the same command again to continue where you left off.\n");
  }
  return 0;
}

int runExport(const cli::Args& args) {
  if (args.positional().size() != 1) return reportError("study export: expected STUDY (see --help)");
  const auto outDir = args.value("out");
  if (!outDir) return reportError("study export: --out DIR is required");
  auto database = openDbToRead(args);
  if (!database) return reportError(database.error().message);
  auto protocol = resolveStudy(*database, args.positional()[0]);
  if (!protocol) return reportError(protocol.error().message);
  auto exporter = StudyExport::prepare(*database, *protocol, *outDir);
  if (!exporter) return reportError(exporter.error().message);
  terminalFprintf(stderr, "exporting study %s: %zu rows from %zu participant(s)\n", protocol->id.c_str(),
               exporter->rowCount(), exporter->participantCount());
  while (!exporter->done()) {
    terminalFprintf(stderr, "[%zu/%zu] %s\n", exporter->written() + 1, exporter->fileCount(), exporter->nextName().c_str());
    if (auto s = exporter->writeNext(); !s) return reportError(s.error().message);
  }
  terminalPrintf("wrote %zu files to %s\n", exporter->fileCount(), outDir->c_str());
  return 0;
}

// The study's design for reading bundles: stored in the target or a source database, else STUDY
// as a study file or shipped study.
Result<quiz::StudyProtocol> mergeDesign(db::Database* target, std::vector<db::Connection>& databases,
                                        const std::string& spec) {
  if (target) {
    auto stored = db::findStudy(*target, spec);
    if (!stored) return tl::unexpected(stored.error());
    if (*stored) return **stored;
  }
  for (auto& source : databases) {
    auto there = db::findStudy(source.get(), spec);
    if (!there) return tl::unexpected(withContext(source.path(), there.error()));
    if (*there) return **there;
  }
  auto defined = findStudyDefinition(spec);
  if (!defined) return tl::unexpected(defined.error());
  if (!*defined)
    return fail(ErrorKind::NotFound, "no study '" + spec + "' to read the bundles against (not stored in --db " +
                                         "or a source database, not a file, not shipped)");
  return **defined;
}

int runMerge(const cli::Args& args) {
  if (args.positional().size() < 2)
    return reportError("study merge: expected STUDY and one or more SOURCE databases or export folders");
  std::string studyId = args.positional()[0];
  std::vector<db::Connection> opened;
  opened.reserve(args.positional().size() - 1);
  std::vector<std::string> bundleFolders;
  std::vector<bool> isBundle;  // per SOURCE, in the order given
  for (std::size_t i = 1; i < args.positional().size(); ++i) {
    const std::string& location = args.positional()[i];
    std::error_code ec;
    if (fs::is_directory(location, ec)) {  // an export bundle (study export --out)
      bundleFolders.push_back(location);
      isBundle.push_back(true);
      continue;
    }
    db::OpenOptions options;
    options.create = false;  // a mistyped source must not become a new, empty database
    auto source = db::openDatabase(location, options);
    if (!source) return reportError("study merge: " + source.error().message);
    opened.push_back(std::move(*source));
    isBundle.push_back(false);
  }
  // The target is created only once every source has been opened and read, so that a mistyped
  // source or a bad bundle leaves no new database behind.
  auto existing = db::openExistingDatabase(args.db());
  if (!existing) return reportError(existing.error().message);
  std::optional<db::Connection> database = std::move(*existing);
  std::optional<quiz::StudyProtocol> design;
  std::vector<std::vector<quiz::StudyResponseRow>> bundles;
  bundles.reserve(bundleFolders.size());
  if (!bundleFolders.empty()) {
    auto found = mergeDesign(database ? &database->get() : nullptr, opened, studyId);
    if (!found) return reportError("study merge: " + found.error().message);
    design = std::move(*found);
    studyId = design->id;
    for (const auto& folder : bundleFolders) {
      auto rows = readStudyBundle(folder, *design);
      if (!rows) return reportError("study merge: " + rows.error().message);
      bundles.push_back(std::move(*rows));
    }
  }
  if (!database) {
    auto created = openDb(args);
    if (!created) return reportError(created.error().message);
    database = std::move(*created);
  }
  for (const auto& source : opened)
    if (source.path() == database->path()) return reportError("study merge: " + source.path() + " is the --db database itself");
  std::vector<db::StudyMergeSource> sources;
  for (std::size_t i = 0, nextDb = 0, nextBundle = 0; i < isBundle.size(); ++i) {
    if (isBundle[i]) {
      sources.push_back({bundleFolders[nextBundle], nullptr, &bundles[nextBundle]});
      ++nextBundle;
    } else {
      sources.push_back({opened[nextDb].path(), &opened[nextDb].get(), nullptr});
      ++nextDb;
    }
  }
  auto report = db::mergeStudy(*database, sources, studyId, design ? &*design : nullptr);
  if (!report) return reportError("study merge: " + report.error().message);
  for (const auto& from : report->sources)
    terminalPrintf("%s: %d participant(s) added, %d already there%s\n", from.name.c_str(), from.added, from.alreadyThere,
                   from.withdrawals ? (", " + std::to_string(from.withdrawals) + " withdrawal(s) carried").c_str() : "");
  terminalPrintf("study %s in %s: %d participant(s)\n", studyId.c_str(), database->path().c_str(), report->participants);
  terminalPrintf("counterbalancing: %s over the %zu rows of one cycle; participants per row used:",
              report->balanced() ? "balanced" : "NOT balanced", report->cycle);
  const char* separator = " ";
  for (const auto& [row, used] : report->designRows) {
    terminalPrintf("%srow %zu ×%d", separator, row, used);
    separator = ", ";
  }
  terminalPrintf("\n");
  if (!report->offDesign.empty()) {
    terminalPrintf("trials following no row of the design:");
    for (const auto& id : report->offDesign) terminalPrintf(" %s", id.c_str());
    terminalPrintf("\n");
  }
  if (!report->balanced())
    terminalPrintf("(some rows are used more often than others, as when each machine starts at row 0: order effects are not cancelled as they are on one machine or a class server)\n");
  return 0;
}

}  // namespace

int runStudyWithdraw(const cli::Args& args);  // cmd_study_withdraw.cpp

int runStudy(const Argv& argv) {
  if (argv.empty() || argv[0] == "--help" || argv[0] == "-h") {
    terminalPrintf("%s", kStudyHelp);
    return argv.empty() ? 2 : 0;
  }
  const std::string verb = argv[0];
  auto args = cli::Args::parse(Argv(argv.begin() + 1, argv.end()), {"participant", "group", "answers", "out", "owner", "reason"},
                               {"exclude"});
  if (!args) return reportError("study " + verb + ": " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kStudyHelp);
    return 0;
  }
  if (verb == "register") return runRegister(*args);
  if (verb == "list") return runList(*args);
  if (verb == "run") return runRun(*args);
  if (verb == "status") return runStatus(*args);
  if (verb == "export") return runExport(*args);
  if (verb == "merge") return runMerge(*args);
  if (verb == "withdraw") return runStudyWithdraw(*args);
  return reportError("study: unknown action '" + verb + "' (register, list, run, status, export, merge, withdraw)", 2);
}

}  // namespace at::app
