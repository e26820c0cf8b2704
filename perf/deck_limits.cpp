// Time to refuse the deck shapes that once stalled the reader (issue 22: a 300 k-character
// scalar took 28-59 s, a 1e5-item list 34 s, a 4 MB scalar over 10 minutes), and to read the
// costliest decks the limits of docs/deck.md still admit. Each shape is parsed `repeats` times
// and its median wall time printed; tests/io/tstDeck.hpp checks the messages.
// Usage: perishell_perf_deck_limits [repeats]
#include <perishell/io/deck.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace {

const std::string header = "perishell:\n  version: 1\n  title: base\n";

std::string flowMap(const int depth) {
  std::string flow = "1";
  for (int level = 0; level < depth; ++level) flow = "{a: " + flow + "}";
  return flow;
}

std::vector<std::pair<std::string, std::string>> shapes() {
  std::vector<std::pair<std::string, std::string>> decks;
  decks.emplace_back("over 1 MiB", header + "# " + std::string(perishell::maxDeckBytes, 'x') + "\n");
  decks.emplace_back("300 k-character scalar", header + "  notes: " + std::string(300000, 'a') + "\n");
  std::string items;
  for (int k = 0; k < 100000; ++k) items += (k ? ", " : "") + std::to_string(k % 10);
  decks.emplace_back("1e5-item flow list", header + "  notes: [" + items + "]\n");
  std::string shortLines;
  for (int k = 0; k < 20000; ++k) shortLines += "    k" + std::to_string(k) + ": 1\n";
  decks.emplace_back("20,000 entries", header + "  notes:\n" + shortLines);
  std::string block;
  for (int group = 0; group < 1800; ++group) {
    block += "  b" + std::to_string(group) + ":\n";
    for (int level = 0; level < 9; ++level) block += std::string(4 + 2 * level, ' ') + "k:\n";
    block += std::string(22, ' ') + "x: 1\n";
  }
  decks.emplace_back("19,900 entries 11 deep (admitted)", header + block);
  std::string flowMaps;
  for (int k = 0; k < 1800; ++k) flowMaps += "  n" + std::to_string(k) + ": " + flowMap(10) + "\n";
  decks.emplace_back("1,800 flow maps 10 deep (admitted)", header + flowMaps);
  return decks;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  std::printf("%-36s %12s %10s  %s\n", "deck shape", "bytes", "median s", "refusal");
  for (const auto& [name, text] : shapes()) {
    std::vector<double> seconds;
    std::string refusal;
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      try {
        perishell::parseDeck(text, "shape.yaml");
        refusal = "(accepted)";
      } catch (const perishell::DeckError& error) {
        refusal = error.reason().substr(0, 60);
      }
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(seconds.begin(), seconds.end());
    std::printf("%-36s %12zu %10.4f  %s\n", name.c_str(), text.size(), seconds[seconds.size() / 2], refusal.c_str());
  }
  return 0;
}
