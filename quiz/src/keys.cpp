#include "quiz/keys.h"

#include <algorithm>
#include <tuple>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "volume/mask.h"

namespace at::quiz {
namespace {

std::string mmText(double mm) {
  if (!std::isfinite(mm)) return "unreachable";
  std::ostringstream out;
  out.precision(3);
  out << mm << " mm";
  return out.str();
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

bool contains(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

}  // namespace

Result<int> relationKey(const RelationSpec& spec, const StructureDistances& distances) {
  if (spec.candidates.size() < 2) return fail("relation from '" + spec.from + "': needs at least 2 candidates");
  std::vector<double> d;
  for (const std::string& candidate : spec.candidates) {
    if (candidate == spec.from) return fail("relation from '" + spec.from + "': candidates include the structure itself");
    const auto it = distances.find(candidate);
    if (it == distances.end()) {
      return fail("relation from '" + spec.from + "': no distance for candidate '" + candidate + "'");
    }
    d.push_back(it->second);
  }
  if (spec.kind == RelationKind::Nearest) {
    std::vector<std::size_t> idx(d.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return d[a] < d[b]; });
    const double best = d[idx[0]], second = d[idx[1]];
    if (!std::isfinite(best)) return fail("relation from '" + spec.from + "': no candidate is reachable");
    if (second - best <= kRelationMargin * std::max(best, 1e-9)) {
      return fail("relation from '" + spec.from + "': nearest is ambiguous: '" + spec.candidates[idx[0]] + "' at " +
                  mmText(best) + " and '" + spec.candidates[idx[1]] + "' at " + mmText(second));
    }
    return int(idx[0]);
  }
  if (!(spec.thresholdMm > 0)) return fail("relation from '" + spec.from + "': reachable needs threshold_mm > 0");
  std::vector<int> within;
  std::string listing;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d[i] <= spec.thresholdMm) within.push_back(int(i));
    listing += (listing.empty() ? "" : ", ") + spec.candidates[i] + " " + mmText(d[i]);
  }
  if (within.size() != 1) {
    return fail("relation from '" + spec.from + "': " + std::to_string(within.size()) + " candidates within " +
                mmText(spec.thresholdMm) + " (need exactly 1): " + listing);
  }
  return within.front();
}

std::vector<std::string> marchLabels(const LabelMap& labels, const std::vector<Structure>& structures,
                                     const Vec3& entryMm, const Vec3& targetMm) {
  std::vector<std::string> met;
  const Geometry& g = labels.geometry;
  if (labels.empty()) return met;
  const double step = 0.25 * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  const Vec3 delta = targetMm - entryMm;
  const int samples = std::max(1, int(std::ceil(norm(delta) / step)));
  std::uint16_t previous = 0;
  for (int s = 0; s <= samples; ++s) {
    const Vec3 p = entryMm + (double(s) / samples) * delta;
    const Vec3 ijk = g.patientToIndex(p);
    const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
    if (!g.dims.contains(i, j, k)) continue;
    const std::uint16_t label = labels.at(i, j, k);
    if (label == 0 || label == previous) continue;
    previous = label;
    for (const Structure& structure : structures) {
      if (structure.label == label && !contains(met, structure.id)) met.push_back(structure.id);
    }
  }
  return met;
}

std::vector<std::string> nearestStructures(const std::string& targetId, const StructureDistances& distances,
                                           int count, const std::vector<std::string>& exclude) {
  std::vector<std::pair<double, std::string>> ranked;
  for (const auto& [id, d] : distances) {
    if (id == targetId || !std::isfinite(d) || contains(exclude, id)) continue;
    ranked.emplace_back(d, id);
  }
  std::sort(ranked.begin(), ranked.end());
  std::vector<std::string> out;
  for (std::size_t i = 0; i < ranked.size() && int(out.size()) < count; ++i) out.push_back(ranked[i].second);
  return out;
}

Result<std::vector<std::string>> neighbourhoodDistractors(const std::string& targetId,
                                                          const StructureDistances& distances, int count,
                                                          KeyComputer& keys) {
  auto centre = keys.centroidMm(targetId);
  if (!centre) return tl::unexpected(centre.error());
  std::vector<std::tuple<double, double, std::string>> ranked;
  for (const auto& [id, d] : distances) {
    if (id == targetId || !std::isfinite(d)) continue;
    auto other = keys.centroidMm(id);
    if (!other) return tl::unexpected(other.error());
    ranked.emplace_back(norm(*other - *centre), d, id);
  }
  std::sort(ranked.begin(), ranked.end());
  std::vector<std::string> out;
  for (std::size_t i = 0; i < ranked.size() && int(out.size()) < count; ++i) out.push_back(std::get<2>(ranked[i]));
  return out;
}

std::vector<std::string> stableShuffle(std::vector<std::string> items, const std::string& seed) {
  std::uint64_t state = fnv1a(seed);
  for (std::size_t i = items.size(); i > 1; --i) {
    const std::size_t j = std::size_t(splitmix64(state) % i);
    std::swap(items[i - 1], items[j]);
  }
  return items;
}

// ---------------------------------------------------------------------------------------------

DatasetKeyComputer::DatasetKeyComputer(const Dataset& dataset, DistanceFieldFunction distanceField)
    : dataset_(dataset), distanceField_(std::move(distanceField)) {}

bool DatasetKeyComputer::hasStructure(const std::string& structureId) const {
  for (const Structure& s : dataset_.structures) {
    if (s.id == structureId) return true;
  }
  return false;
}

Result<StructureDistances> DatasetKeyComputer::distancesFrom(const std::string& structureId) {
  if (const auto it = cache_.find(structureId); it != cache_.end()) return it->second;
  const Structure* source = nullptr;
  for (const Structure& s : dataset_.structures) {
    if (s.id == structureId) source = &s;
  }
  if (!source) return fail("dataset '" + dataset_.id + "' has no structure '" + structureId + "'");
  const Mask seeds = structureMask(dataset_.labels, source->label);
  Result<FloatVolume> field = distanceField_(seeds);
  if (!field) return tl::unexpected(withContext("distances from '" + structureId + "'", field.error()));
  if (!(field->dims() == dataset_.labels.dims())) {
    return fail("distances from '" + structureId + "': field is " + field->dims().toString() + " but labels are " +
                dataset_.labels.dims().toString());
  }
  std::vector<double> minimum(65536, std::numeric_limits<double>::infinity());
  for (std::size_t v = 0; v < field->voxels.size(); ++v) {
    const std::uint16_t label = dataset_.labels.voxels[v];
    if (label != 0) minimum[label] = std::min(minimum[label], double(field->voxels[v]));
  }
  StructureDistances distances;
  for (const Structure& s : dataset_.structures) distances[s.id] = minimum[s.label];
  cache_[structureId] = distances;
  return distances;
}

Result<Vec3> DatasetKeyComputer::centroidMm(const std::string& structureId) {
  for (const Structure& s : dataset_.structures) {
    if (s.id != structureId) continue;
    const MaskStats stats = measureLabel(dataset_.labels, s.label);
    if (stats.voxelCount == 0) return fail("structure '" + structureId + "' has no voxels in '" + dataset_.id + "'");
    return stats.centroidMm;
  }
  return fail("dataset '" + dataset_.id + "' has no structure '" + structureId + "'");
}

Result<std::vector<std::string>> DatasetKeyComputer::structuresAlong(const Vec3& entryMm, const Vec3& targetMm) {
  return marchLabels(dataset_.labels, dataset_.structures, entryMm, targetMm);
}

// ---------------------------------------------------------------------------------------------

Result<ResolvedQuestion> resolveQuestion(const Question& question, KeyComputer& keys) {
  const std::string where = "question " + (question.id.empty() ? std::string("(no id)") : question.id);
  const auto bad = [&](const std::string& field, const std::string& problem) {
    return fail(where + ": " + field + ": " + problem);
  };
  const auto unknown = [&](const std::string& field, const std::string& id) {
    return bad(field, "unknown structure '" + id + "'");
  };
  if (question.id.empty()) return bad("id", "missing");
  if (question.target.empty()) return bad("target", "missing");
  if (!keys.hasStructure(question.target)) return unknown("target", question.target);

  ResolvedQuestion resolved;
  resolved.question = question;
  switch (question.kind) {
    case QuestionKind::Locate:
      if (!(question.toleranceMm >= 0)) return bad("tolerance_mm", "must be >= 0");
      break;
    case QuestionKind::Name:
      break;
    case QuestionKind::Identify: {
      if (!question.choices.empty()) {
        for (const std::string& id : question.choices) {
          if (!keys.hasStructure(id)) return unknown("choices", id);
          if (std::count(question.choices.begin(), question.choices.end(), id) > 1) {
            return bad("choices", "'" + id + "' listed twice");
          }
        }
        if (question.choices.size() < 2) return bad("choices", "needs at least 2");
        const auto it = std::find(question.choices.begin(), question.choices.end(), question.target);
        if (it == question.choices.end()) return bad("choices", "must contain the target '" + question.target + "'");
        resolved.choices = question.choices;
      } else {
        if (question.distractors < 1) return bad("distractors", "must be >= 1");
        auto distances = keys.distancesFrom(question.target);
        if (!distances) return tl::unexpected(withContext(where, distances.error()));
        auto neighbours = neighbourhoodDistractors(question.target, *distances, question.distractors, keys);
        if (!neighbours) return tl::unexpected(withContext(where, neighbours.error()));
        std::vector<std::string> choices = std::move(*neighbours);
        if (choices.empty()) return bad("distractors", "no other structure is reachable from the target");
        choices.push_back(question.target);
        resolved.choices = stableShuffle(std::move(choices), question.id);
      }
      resolved.keyChoice = int(std::find(resolved.choices.begin(), resolved.choices.end(), question.target) -
                               resolved.choices.begin());
      break;
    }
    case QuestionKind::Relation: {
      const RelationSpec& spec = question.relation;
      if (!keys.hasStructure(spec.from)) return unknown("relation.from", spec.from);
      for (const std::string& id : spec.candidates) {
        if (!keys.hasStructure(id)) return unknown("relation.candidates", id);
      }
      auto distances = keys.distancesFrom(spec.from);
      if (!distances) return tl::unexpected(withContext(where, distances.error()));
      auto key = relationKey(spec, *distances);
      if (!key) return tl::unexpected(withContext(where, key.error()));
      resolved.choices = spec.candidates;
      resolved.keyChoice = *key;
      break;
    }
    case QuestionKind::Order: {
      const OrderSpec& spec = question.order;
      const auto endpoint = [&](const std::optional<Vec3>& point, const std::string& structure,
                                const std::string& name) -> Result<Vec3> {
        if (point && !structure.empty()) return bad("order." + name, "give a point or a structure, not both");
        if (point) return *point;
        if (structure.empty()) return bad("order." + name, "missing (a point in mm or a structure id)");
        if (!keys.hasStructure(structure)) return unknown("order." + name + "_structure", structure);
        auto centroid = keys.centroidMm(structure);
        if (!centroid) return tl::unexpected(withContext(where, centroid.error()));
        return *centroid;
      };
      auto entry = endpoint(spec.entryMm, spec.entryStructure, "entry");
      if (!entry) return tl::unexpected(entry.error());
      auto target = endpoint(spec.targetMm, spec.targetStructure, "target");
      if (!target) return tl::unexpected(target.error());
      auto met = keys.structuresAlong(*entry, *target);
      if (!met) return tl::unexpected(withContext(where, met.error()));
      if (met->size() < 2) {
        return bad("order", "the path meets " + std::to_string(met->size()) + " structure(s); an order needs 2 or more");
      }
      resolved.keyOrder = *met;
      std::vector<std::string> offered = *met;
      if (spec.extraChoices > 0) {
        auto distances = keys.distancesFrom(question.target);
        if (!distances) return tl::unexpected(withContext(where, distances.error()));
        for (const std::string& id : nearestStructures(question.target, *distances, spec.extraChoices, *met)) {
          offered.push_back(id);
        }
      }
      offered = stableShuffle(std::move(offered), question.id);
      if (std::equal(met->begin(), met->end(), offered.begin())) {
        std::rotate(offered.begin(), offered.begin() + 1, offered.end());  // never offer the answer as is
      }
      resolved.choices = std::move(offered);
      break;
    }
  }
  return resolved;
}

}  // namespace at::quiz
