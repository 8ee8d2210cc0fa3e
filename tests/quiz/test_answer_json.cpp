#include <doctest/doctest.h>

#include "quiz/answer_json.h"

using namespace at::quiz;

TEST_CASE("AnswerJson_ParsesEveryPlayLineFormAndRoundTrips") {
  auto choice = answerFromJson(R"({"choice": 2})");
  REQUIRE(choice);
  CHECK(*choice->choice == 2);
  auto text = answerFromJson(R"({"text": "Cochlea; DROP TABLE users; \"quoted\""})");
  REQUIRE(text);
  CHECK(*text->text == "Cochlea; DROP TABLE users; \"quoted\"");
  auto pick = answerFromJson(R"({"pick": "stapes", "distance_mm": 0.3})");
  REQUIRE(pick);
  CHECK(pick->pick->structure == "stapes");
  CHECK(pick->pick->distanceMm == doctest::Approx(0.3));
  auto nothing = answerFromJson(R"({"pick": null})");
  REQUIRE(nothing);
  CHECK(nothing->pick->structure.empty());
  CHECK(nothing->pick->distanceMm < 0);
  auto order = answerFromJson(R"({"order": ["a", "b"]})");
  REQUIRE(order);
  CHECK(*order->order == std::vector<std::string>{"a", "b"});

  for (const auto* a : {&*choice, &*text, &*pick, &*order}) {
    auto again = answerFromJson(answerToJson(*a));
    REQUIRE(again);
    CHECK(answerToJson(*again) == answerToJson(*a));
  }
}

TEST_CASE("AnswerJson_MalformedLinesAreErrorsSayingWhy") {
  const auto message = [](const char* line) {
    auto r = answerFromJson(line);
    REQUIRE_FALSE(r);
    return r.error().message;
  };
  CHECK(message("{choice: 2}").find("not valid JSON") != std::string::npos);
  CHECK(message("[1]").find("object") != std::string::npos);
  CHECK(message(R"({"choice": "2"})").find("choice") != std::string::npos);
  CHECK(message(R"({"colour": 2})").find("unknown field 'colour'") != std::string::npos);
  CHECK(message(R"({})").find("no answer") != std::string::npos);
  CHECK(message(R"({"choice": 1, "text": "x"})").find("more than one") != std::string::npos);
  CHECK(message(R"({"distance_mm": 0.3})").find("only allowed with pick") != std::string::npos);
  CHECK(message(R"({"pick": "stapes", "distance_mm": -1})").find("distance_mm") != std::string::npos);
  CHECK(message(R"({"order": ["a", 3]})").find("order") != std::string::npos);
  // A number beyond a double: an error with the column and field, not an escaping exception.
  CHECK(message(R"({"pick": "stapes", "distance_mm": 1e999})") ==
        "column 40, field 'distance_mm': number 1e999 is out of range (beyond ±1.8e308)");
  CHECK(message(R"({"choice": 1e309})").find("field 'choice': number 1e309 is out of range") != std::string::npos);
  // Keys quoted printably: no escape sequence reaches the terminal.
  CHECK(message("{\"\\u001b[2J\": 1}") == "unknown field '\\x1b[2J' (expected choice, text, pick with distance_mm, pixel and view, or order)");
}

TEST_CASE("AnswerJson_APickOnAPictureKeepsItsPixelAndView_WhichAClassServerGrades") {
  Answer a;
  a.pick = Pick{.structure = "malleus", .distanceMm = 0.25, .pixel = std::array<int, 2>{181, 7}, .view = "400x300-00ff"};
  const std::string json = answerToJson(a);
  auto again = answerFromJson(json);
  REQUIRE(again);
  REQUIRE(again->pick);
  CHECK(again->pick->structure == "malleus");
  CHECK(again->pick->pixel == std::array<int, 2>{181, 7});
  CHECK(again->pick->view == "400x300-00ff");
  CHECK(answerToJson(*again) == json);
  // A pixel alone (an exam item's, graded elsewhere) has no view.
  auto exam = answerFromJson(R"({"pick": "", "pixel": [3, 4]})");
  REQUIRE(exam);
  CHECK(exam->pick->view.empty());
  const auto message = [](const char* line) {
    auto r = answerFromJson(line);
    return r ? std::string() : r.error().message;
  };
  CHECK(message(R"({"pick": "malleus", "pixel": [1.5, 2]})") == "pixel: must be [x, y] in whole pixels");
  CHECK(message(R"({"pick": "malleus", "pixel": [1, 2, 3]})") == "pixel: must be [x, y] in whole pixels");
  CHECK(message(R"({"pick": "malleus", "view": "v"})") == "view: must be the id of the view a pixel was picked on");
  CHECK(message(R"({"view": "v", "choice": 1})") == "view: only allowed with pick");
}
