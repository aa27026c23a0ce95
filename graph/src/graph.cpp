#include "kg/graph/graph.hpp"

#include <set>

namespace kg::graph {

const NodeInstance* Graph::find_node(const std::string& id) const {
  for (const NodeInstance& n : nodes)
    if (n.id == id) return &n;
  return nullptr;
}

std::vector<std::pair<std::size_t, std::size_t>> Graph::connection_ends() const {
  std::map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < nodes.size(); ++i) index[nodes[i].id] = i;
  std::vector<std::pair<std::size_t, std::size_t>> ends;
  ends.reserve(connections.size());
  for (const Connection& c : connections) {
    auto from = index.find(c.from.node), to = index.find(c.to.node);
    if (from == index.end() || to == index.end())
      throw Error(
          "connection " + c.from.to_string() + " -> " + c.to.to_string() + " names a node not in the graph",
          c.where);
    ends.emplace_back(from->second, to->second);
  }
  return ends;
}

std::vector<std::size_t> Graph::topological_order() const {
  std::vector<std::vector<std::size_t>> next(nodes.size());
  std::vector<std::size_t> pending(nodes.size(), 0);
  for (const auto& [from, to] : connection_ends()) {
    next[from].push_back(to);
    ++pending[to];
  }
  // Kahn's algorithm; the ordered set makes the order stable: file order among ready nodes.
  std::set<std::size_t> ready;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (pending[i] == 0) ready.insert(i);
  std::vector<std::size_t> order;
  order.reserve(nodes.size());
  while (!ready.empty()) {
    const std::size_t i = *ready.begin();
    ready.erase(ready.begin());
    order.push_back(i);
    for (std::size_t j : next[i])
      if (--pending[j] == 0) ready.insert(j);
  }
  if (order.size() != nodes.size()) {
    std::string stuck;
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (pending[i] != 0) stuck += (stuck.empty() ? "" : ", ") + nodes[i].id;
    throw Error("the graph has a cycle through " + stuck, {file.string(), 0, 0});
  }
  return order;
}

}  // namespace kg::graph
