// Small string helpers that several modules need (ASCII only: ids, file names, user input).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace at::str {

// ASCII lower case ("Cochlea.NII" → "cochlea.nii").
std::string lower(std::string_view text);

// Without leading and trailing blanks (space, tab, CR, LF).
std::string trim(std::string_view text);

bool startsWith(std::string_view text, std::string_view prefix);
bool endsWith(std::string_view text, std::string_view suffix);

// An identifier made from a name: lower-case letters and digits, every other run of characters
// one '_', none at either end ("Vertebrae L1" → "vertebrae_l1", "kidney-left (2)" → "kidney_left_2").
std::string identifier(std::string_view name);

// The items joined with `separator` ({"a", "b"}, ", " → "a, b").
std::string join(const std::vector<std::string>& items, std::string_view separator);

// A count with its noun in the right number: "1 lesson", "2 lessons", "0 lessons" (`plural`
// defaults to `singular` + "s").
std::string countOf(long long n, std::string_view singular, std::string_view plural = {});

}  // namespace at::str
