// anatomy-tutor analytics COURSE: the instructor's view of a class (lessons/analytics.h) — lesson
// completion, the hardest structures, question difficulty (Elo with an uncertainty factor), each
// student's predicted recall (FSRS) and exam results — as text with bar charts, or as CSV.
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "cli_args.h"
#include "commands.h"
#include "core/atomic_file.h"
#include "db/analytics_store.h"
#include "core/strings.h"
#include "learning_session.h"
#include "quiz/study_report.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kAnalyticsHelp =
    "usage: anatomy-tutor analytics COURSE [--group GROUP] [--csv [--out DIR]] [--db PATH]\n\n"
    "The instructor's view of a class (every student, or the students of --group):\n"
    "  lessons     how many students started and finished each lesson (completion = finished / class)\n"
    "  structures  the structures the class finds hardest: share of right answers, the class's mean\n"
    "              FSRS difficulty (1 easy … 10 hard) and mean predicted recall now\n"
    "  questions   each question's difficulty on the Elo scale (1500 = average; higher = harder),\n"
    "              replayed over the class's answers with the uncertainty factor U(n) = 1/(1 + 0.05 n)\n"
    "  students    each student's predicted recall now (FSRS retrievability, mean over the structures\n"
    "              taught), the weakest structure, how many are due, lessons finished, latest exam score\n"
    "  exams       attempts, mean score, pass rate\n"
    "  --csv       CSV instead of text: one tidy table on stdout (table,id,name,metric,value), or with\n"
    "              --out DIR one wide file per table (lessons.csv, structures.csv, questions.csv,\n"
    "              students.csv, exams.csv) and the class's review log as revlog.csv in the form FSRS\n"
    "              optimisers read (card_id = student/structure, review_time in ms, review_rating 1-4,\n"
    "              review_state 0 new, 1 learning, 2 review, 3 relearning, review_duration in ms).\n"
    "              Text cells that begin with =, +, -, @, a tab or CR (a name such as \"=SUM(A1)\") get a\n"
    "              leading apostrophe so that spreadsheets do not run them as formulas; numbers, negative\n"
    "              ones included, are written as plain numbers\n";

std::string bar(double share, int width = 20) {
  const int full = int(std::lround(std::clamp(share, 0.0, 1.0) * width));
  std::string s;
  for (int i = 0; i < width; ++i) s += i < full ? "█" : "·";
  return s;
}

std::string percent(std::optional<double> share) {
  if (!share) return "–";
  char t[16];
  std::snprintf(t, sizeof t, "%.0f%%", 100 * *share);
  return t;
}

std::string number(double v, int decimals) {
  char t[32];
  std::snprintf(t, sizeof t, "%.*f", decimals, v);
  return t;
}

// One CSV field: text (names, ids, titles: what students and instructors typed) or a number this
// program formatted. Text gets quiz::csvCell's formula guard (a leading apostrophe before = + - @
// TAB CR) and quoting; a number is written as it is, so a negative one stays a number.
struct Cell {
  std::string value;
  bool text = true;
  Cell(std::string v) : value(std::move(v)) {}  // NOLINT: text by default
  Cell(const char* v) : value(v) {}             // NOLINT
  static Cell num(std::string v) {
    Cell c(std::move(v));
    c.text = false;
    return c;
  }
};

std::string csvField(const Cell& cell) { return cell.text ? quiz::csvCell(cell.value) : quiz::csvQuoted(cell.value); }

Cell count(long long n) { return Cell::num(std::to_string(n)); }
Cell decimal(double v, int decimals) { return Cell::num(number(v, decimals)); }
Cell optionalNumber(std::optional<double> v, int decimals) { return Cell::num(v ? number(*v, decimals) : ""); }

// The tables as rows of fields (first row: the header), shared by both CSV forms.
struct Table {
  std::string name;
  std::vector<std::vector<Cell>> rows;
};

std::vector<Table> tables(const lessons::ClassAnalytics& a) {
  std::vector<Table> out;
  Table lessons{"lessons", {{"lesson", "title", "started", "finished", "completion", "mean_best_score"}}};
  for (const auto& l : a.lessons)
    lessons.rows.push_back({l.lessonId, l.title, count(l.started), count(l.finished), decimal(l.completion, 4),
                            optionalNumber(l.meanBestScore, 4)});
  Table structures{"structures",
                   {{"structure", "name", "answers", "correct", "correct_share", "students", "mean_fsrs_difficulty",
                     "mean_recall"}}};
  for (const auto& s : a.structures)
    structures.rows.push_back({s.structureId, s.name, count(s.answers), count(s.correct), decimal(s.correctShare, 4),
                               count(s.students), decimal(s.meanDifficulty, 4), decimal(s.meanRecall, 4)});
  Table questions{"questions",
                  {{"question", "lesson_or_exam", "structure", "kind", "answers", "correct", "correct_share",
                    "initial_difficulty", "elo_difficulty"}}};
  for (const auto& q : a.questions)
    questions.rows.push_back({q.questionId, q.lessonId, q.structureId, q.kind, count(q.answers), count(q.correct),
                              decimal(q.correctShare, 4), decimal(q.initialDifficulty, 1), decimal(q.difficulty, 2)});
  Table students{"students",
                 {{"student", "group", "taught", "due", "mean_recall", "weakest_structure", "weakest_recall",
                   "lessons_finished", "exam_score"}}};
  for (const auto& s : a.students)
    students.rows.push_back({s.name, s.group, count(s.taught), count(s.due), optionalNumber(s.meanRecall, 4),
                             s.weakestStructure,
                             optionalNumber(s.weakestStructure.empty() ? std::nullopt : std::optional(s.weakestRecall), 4),
                             count(s.lessonsFinished), optionalNumber(s.examScore, 4)});
  Table exams{"exams", {{"exam", "title", "attempts", "finished", "mean_score", "pass_rate"}}};
  for (const auto& e : a.exams)
    exams.rows.push_back({e.examId, e.title, count(e.attempts), count(e.finished), optionalNumber(e.meanScore, 4),
                          optionalNumber(e.passRate, 4)});
  for (Table* t : {&lessons, &structures, &questions, &students, &exams}) out.push_back(std::move(*t));
  return out;
}

// One tidy CSV: table, the row's id (its first field), its name (the second), metric, value.
void printLongCsv(const std::vector<Table>& all) {
  terminalPrintf("table,id,name,metric,value\n");
  for (const Table& t : all) {
    const auto& header = t.rows.front();
    for (std::size_t r = 1; r < t.rows.size(); ++r)
      for (std::size_t c = 2; c < header.size(); ++c)
        terminalPrintf("%s,%s,%s,%s,%s\n", t.name.c_str(), csvField(t.rows[r][0]).c_str(), csvField(t.rows[r][1]).c_str(),
                    header[c].value.c_str(), csvField(t.rows[r][c]).c_str());
  }
}

// The review log of the class, one row per answer, oldest first, for an FSRS optimiser.
Table reviewLogTable(const lessons::AnalyticsInput& in) {
  Table t{"revlog", {{"card_id", "student", "structure", "review_time", "review_rating", "review_state", "review_duration"}}};
  std::map<std::int64_t, std::string> names;
  for (const auto& u : in.students) names[u.id] = u.name;
  std::vector<const lessons::ClassAnswer*> ordered;
  for (const auto& a : in.answers) ordered.push_back(&a);
  std::sort(ordered.begin(), ordered.end(), [](const auto* x, const auto* y) {
    return x->answeredAt != y->answeredAt ? x->answeredAt < y->answeredAt : x->order < y->order;
  });
  for (const auto* a : ordered)
    t.rows.push_back({names[a->userId] + "/" + a->structureId, names[a->userId], a->structureId, count(a->answeredAt * 1000),
                      count(int(a->rating)), count(int(a->phaseBefore)), count(a->latencyMs)});
  return t;
}

Status writeWideCsv(const std::vector<Table>& all, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return fail(dir.string() + ": cannot create the folder (" + ec.message() + ")");
  for (const Table& t : all) {
    const auto path = dir / (t.name + ".csv");
    std::string text;
    for (const auto& row : t.rows) {
      for (std::size_t c = 0; c < row.size(); ++c) text += (c ? "," : "") + csvField(row[c]);
      text += "\n";
    }
    if (auto ok = writeFileAtomically(path.string(), text); !ok) return ok;
    terminalPrintf("wrote %s (%s)\n", path.string().c_str(), str::countOf(long(t.rows.size() - 1), "row").c_str());
  }
  return {};
}

void printText(const lessons::ClassAnalytics& a, const lessons::Course& course) {
  terminalPrintf("Analytics: %s (%s) — class of %s, %s\n", rowCell(course.title).c_str(), course.id.c_str(),
              str::countOf(a.classSize, "student").c_str(), str::countOf(a.answers, "answer").c_str());
  terminalPrintf("\nLesson completion (finished / class)\n");
  for (const auto& l : a.lessons)
    terminalPrintf("  %-26s %s %4s  %3d started, %3d finished, mean best score %s%s\n", l.lessonId.c_str(),
                bar(l.completion).c_str(), percent(l.completion).c_str(), l.started, l.finished,
                l.meanBestScore ? number(*l.meanBestScore, 2).c_str() : "–",
                l.scoresUnknown ? (", " + std::to_string(l.scoresUnknown) + " finished waiting for keys").c_str() : "");
  terminalPrintf("\nHardest structures (share of right answers; FSRS difficulty 1 easy … 10 hard; predicted recall now)\n");
  for (const auto& s : a.structures)
    terminalPrintf("  %-30s %s %4s right of %4d   difficulty %4.1f   recall %4s (%s)\n", s.name.c_str(),
                bar(s.correctShare).c_str(), percent(s.correctShare).c_str(), s.answers, s.meanDifficulty,
                percent(s.students ? std::optional<double>(s.meanRecall) : std::nullopt).c_str(),
                str::countOf(s.students, "student").c_str());
  terminalPrintf("\nQuestions by difficulty (Elo: 1500 = average, higher = harder)\n");
  for (const auto& q : a.questions)
    if (q.answers > 0)
      terminalPrintf("  %-48s %-8s %6.0f  (%4s right of %d)\n", q.questionId.c_str(), q.kind.c_str(), q.difficulty,
                  percent(q.correctShare).c_str(), q.answers);
  terminalPrintf("\nStudents by predicted recall now (FSRS, mean over the structures taught)\n");
  for (const auto& s : a.students) {
    terminalPrintf("  %-20s %s %4s  %2d taught, %2d due", s.name.c_str(), bar(s.meanRecall.value_or(0), 10).c_str(),
                percent(s.meanRecall).c_str(), s.taught, s.due);
    if (!s.weakestStructure.empty())
      terminalPrintf(", weakest %s (%s)", s.weakestStructure.c_str(), percent(s.weakestRecall).c_str());
    terminalPrintf(", %s finished", str::countOf(s.lessonsFinished, "lesson").c_str());
    if (s.examScore) terminalPrintf(", exam %s", number(*s.examScore, 2).c_str());
    terminalPrintf("\n");
  }
  if (!a.exams.empty()) terminalPrintf("\nExams\n");
  for (const auto& e : a.exams)
    terminalPrintf("  %-28s %s, %d finished, mean score %s, passed %s\n", e.examId.c_str(),
                str::countOf(e.attempts, "attempt").c_str(), e.finished, e.meanScore ? number(*e.meanScore, 2).c_str() : "–",
                percent(e.passRate).c_str());
}

}  // namespace

int runAnalytics(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"group", "out"}, {"csv"});
  if (!args) return reportError("analytics: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kAnalyticsHelp);
    return 0;
  }
  if (args->positional().size() != 1) return reportError("analytics: give exactly one COURSE (see `anatomy-tutor courses`)");
  if (args->has("out") && !args->has("csv")) return reportError("analytics: --out DIR writes CSV files: add --csv");
  auto session = LearningSession::open(args->db());
  if (!session) return reportError("analytics: " + session.error().message);
  auto input = db::loadAnalyticsInput((*session)->database(), (*session)->curriculum(), args->positional()[0],
                                      args->value("group"));
  if (!input) return reportError("analytics: " + input.error().message + " (see `anatomy-tutor courses`)");
  const auto analytics = lessons::computeAnalytics(*input, lessons::UnixSeconds(std::time(nullptr)));
  if (!args->has("csv")) {
    printText(analytics, input->course);
    if (input->waitingAnswers > 0)
      terminalPrintf("\n%s on the class server wait for their answer keys and are not counted yet "
                     "(an instructor publishes them with: anatomy-tutor class keys CODE --db SERVER)\n",
                     str::countOf(input->waitingAnswers, "answer").c_str());
    return 0;
  }
  auto all = tables(analytics);
  if (auto out = args->value("out")) {
    all.push_back(reviewLogTable(*input));
    if (auto st = writeWideCsv(all, *out); !st) return reportError("analytics: " + st.error().message);
    return 0;
  }
  printLongCsv(all);
  return 0;
}

}  // namespace at::app
