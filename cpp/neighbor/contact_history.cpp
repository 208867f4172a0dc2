#include "neighbor/contact_history.hpp"

#include <algorithm>

namespace grainscale {

void HistoryCarry::save(const ContactList& list, PartnerKey key) {
  stride_ = list.history_stride;
  const Index n = list.first.empty() ? 0 : static_cast<Index>(list.first.size()) - 1;
  first_.assign(n + 1, 0);
  keys_.clear();
  values_.clear();
  const Index total = n > 0 ? list.first[n] : 0;
  // One loop over the entries, rows taken from the list's index (index_rows), not a loop per
  // row: rows hold two or three entries and the exit of a loop per row mispredicts at nearly
  // every row (the 200k settle case: 1.8 % of the run in the loop per row).
  const bool indexed = list.owner.size() == static_cast<std::size_t>(total);
  Index row = 0;
  for (Index k = 0; k < total; ++k) {
    if (!list.touching[k]) continue;
    if (indexed)
      row = list.owner[k];
    else  // a list without its index (not made by a build or a load)
      while (list.first[row + 1] <= k) ++row;
    ++first_[row + 1];
    keys_.push_back(key(list.partner[k]));
    const Real* h = list.history.data() + static_cast<std::size_t>(k) * stride_;
    values_.insert(values_.end(), h, h + stride_);
  }
  for (Index i = 0; i < n; ++i) first_[i + 1] += first_[i];  // counts -> row starts
}

void HistoryCarry::restore(const std::vector<Index>& origin, PartnerKey key,
                           ContactList& list) const {
  if (keys_.empty() || stride_ != list.history_stride) return;
  const Index n = static_cast<Index>(list.first.size()) - 1;
  for (Index i = 0; i < n; ++i) {
    const Index o = origin[i];
    if (o < 0) continue;
    const Index b = first_[o], e = first_[o + 1];
    if (b == e) continue;
    for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
      const GlobalId partner_key = key(list.partner[k]);
      for (Index s = b; s < e; ++s) {
        if (keys_[s] != partner_key) continue;
        std::copy(values_.begin() + static_cast<std::size_t>(s) * stride_,
                  values_.begin() + static_cast<std::size_t>(s + 1) * stride_,
                  list.history.begin() + static_cast<std::size_t>(k) * stride_);
        list.touching[k] = 1;
        break;
      }
    }
  }
}

}  // namespace grainscale
