// ContactHistory carry: keeps the per-contact history of a ContactList across a rebuild.
// Entries are keyed by (owner particle, partner key); the partner key is the partner's global
// id for particle pairs and the wall index for wall contacts. Only touching entries are carried;
// everything else starts from zero, as a new contact does.
#pragma once

#include <vector>

#include "core/page_vector.hpp"
#include "core/types.hpp"
#include "neighbor/neighbor_list.hpp"

namespace grainscale {

// The key of a list entry from its partner: the partner's global id (particle pairs: `id` is
// the particles' ids at the time) or, without ids, the partner index itself (walls).
struct PartnerKey {
  const GlobalId* id = nullptr;
  GlobalId operator()(Index partner) const { return id ? id[partner] : GlobalId(partner); }
};

class HistoryCarry {
 public:
  // Saves the touching entries of `list`, keyed by key(partner).
  void save(const ContactList& list, PartnerKey key);
  // Fills the history of a freshly built `list`. origin[i] is the index particle i had when
  // save() ran (-1 for particles added since); key as for save(), of the new partners.
  void restore(const std::vector<Index>& origin, PartnerKey key, ContactList& list) const;
  // Forgets the saved entries, keeping the buffers (rebuilds reuse them).
  void clear() {
    first_.clear();
    keys_.clear();
    values_.clear();
  }
  bool empty() const { return keys_.empty(); }
  std::size_t size() const { return keys_.size(); }

  // Row access (migration between ranks, checkpoints): the entries saved for the particle that
  // had index `row` at save(); rows that were never saved are empty.
  Index row_size(Index row) const {
    return row >= 0 && static_cast<std::size_t>(row) + 1 < first_.size()
               ? first_[row + 1] - first_[row]
               : 0;
  }
  const GlobalId* row_keys(Index row) const { return keys_.data() + first_[row]; }
  const Real* row_values(Index row) const {
    return values_.data() + static_cast<std::size_t>(first_[row]) * stride_;
  }
  int stride() const { return stride_; }
  Index rows() const { return first_.empty() ? 0 : static_cast<Index>(first_.size()) - 1; }
  // Starts an empty carry with `stride` values per entry; rows are then appended in order
  // (row k for the particle whose origin is k).
  void start(int stride) {
    clear();
    stride_ = stride;
    first_.push_back(0);
  }
  void append_row(const GlobalId* keys, const Real* values, Index count) {
    keys_.insert(keys_.end(), keys, keys + count);
    values_.insert(values_.end(), values, values + static_cast<std::size_t>(count) * stride_);
    first_.push_back(static_cast<Index>(keys_.size()));
  }

 private:
  PageVector<Index> first_;
  PageVector<GlobalId> keys_;
  PageVector<Real> values_;
  int stride_ = 0;
};

}  // namespace grainscale
