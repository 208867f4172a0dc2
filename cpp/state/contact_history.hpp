// ContactHistory carry: keeps the per-contact history of a ContactList across a rebuild.
// Entries are keyed by (owner particle, partner key); the partner key is the partner's global
// id for particle pairs and the wall index for wall contacts. Only touching entries are carried;
// everything else starts from zero, as a new contact does.
#pragma once

#include <vector>

#include "core/types.hpp"
#include "neighbor/neighbor_list.hpp"

namespace grainscale {

class HistoryCarry {
 public:
  // Saves the touching entries of `list`; partner_key[k] is the key of entry k.
  void save(const ContactList& list, const std::vector<GlobalId>& partner_key);
  // Fills the history of a freshly built `list`. origin[i] is the index particle i had when
  // save() ran (-1 for particles added since).
  void restore(const std::vector<Index>& origin, const std::vector<GlobalId>& partner_key,
               ContactList& list) const;
  // Forgets the saved entries, keeping the buffers (rebuilds reuse them).
  void clear() {
    first_.clear();
    keys_.clear();
    values_.clear();
  }
  bool empty() const { return keys_.empty(); }
  std::size_t size() const { return keys_.size(); }

 private:
  std::vector<Index> first_;
  std::vector<GlobalId> keys_;
  std::vector<Real> values_;
  int stride_ = 0;
};

}  // namespace grainscale
