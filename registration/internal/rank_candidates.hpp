#pragma once
// LocalizeInCloud's last step, exposed for its unit tests: ranks the verified and refined
// candidates into result->candidates (one instance per place) and result->rejected.

#include <vector>

#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::registration::internal {

/// Accepted candidates by support after refinement (ties: cluster score), one per place: a
/// candidate within options.clustering.duplicate_radius_mm of a kept one is its duplicate; when
/// it converged to the kept one's pose (centre shift + turn x diameter / 2 below the refined
/// support distance) and came from a stronger cluster, it takes the kept one's place and rank.
/// A second orientation at one place with nearly the winner's support, or a planar model, sets
/// result->ambiguous. `options` carries the absolute values LocalizeInCloud derives.
void RankCandidates(std::vector<LocalizationCandidate> refined, const PpfModel& model,
                    const LocalizeOptions& options, LocalizationResult* result);

}  // namespace lasercell::registration::internal
