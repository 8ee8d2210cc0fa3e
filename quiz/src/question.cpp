#include "quiz/question.h"

namespace at::quiz {

const char* toString(QuestionKind kind) {
  switch (kind) {
    case QuestionKind::Locate: return "locate";
    case QuestionKind::Identify: return "identify";
    case QuestionKind::Name: return "name";
    case QuestionKind::Relation: return "relation";
    case QuestionKind::Order: return "order";
  }
  return "locate";
}

Result<QuestionKind> parseQuestionKind(const std::string& text) {
  for (QuestionKind kind : {QuestionKind::Locate, QuestionKind::Identify, QuestionKind::Name,
                            QuestionKind::Relation, QuestionKind::Order}) {
    if (text == toString(kind)) return kind;
  }
  return fail("unknown question kind '" + text + "' (expected locate, identify, name, relation or order)");
}

const char* toString(RelationKind kind) {
  return kind == RelationKind::Nearest ? "nearest" : "reachable";
}

Result<RelationKind> parseRelationKind(const std::string& text) {
  if (text == "nearest") return RelationKind::Nearest;
  if (text == "reachable") return RelationKind::Reachable;
  return fail("unknown relation kind '" + text + "' (expected nearest or reachable)");
}

}  // namespace at::quiz
