// A structured mutation fuzzer for what users hand us (issue 22, docs/reliability.md): the
// shipped small decks and the Gmsh plate, mutated deterministically (byte and line edits, YAML
// punctuation, extreme numbers, truncation), go through the deck reader and the model build, or
// the Gmsh reader. Every input must end in a value or a std::exception whose message starts with
// the file's name and shows no internals (library names, C++ scopes, source files, build paths,
// unless the input itself holds that text and the message quotes it);
// a crash or a sanitizer report fails the test binary, and a runaway input fails it by ctest's
// timeout (the inputs are < 4 kB and take milliseconds; no wall time is asserted here).
#include <perishell/io/deck.hpp>
#include <perishell/mesh/gmsh_reader.hpp>
#include <perishell/model/model.hpp>

#include <test_files.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fuzz_inputs_test {

namespace fs = std::filesystem;

using perishell_test::testDataDirectory;
const auto& readText = perishell_test::readTextFile;

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// One random edit of the text, or (a third of the time) two or three.
std::string mutate(const std::string& seed, std::mt19937_64& random) {
  static const std::string punctuation = "{}[]:,-#&*!|>'\"%@` \n\t0123456789.e+-xyz";
  static const std::vector<std::string> extremes = {"1e308", "-1e308", "1e-320", "0", "-0", "nan", "inf", "-1",
                                                    "99999999999999999999", "0x10", "1e400", "", "~", "null"};
  std::string text = seed;
  const auto below = [&](std::size_t n) { return n == 0 ? std::size_t(0) : std::size_t(random() % n); };
  const int edits = random() % 3 == 0 ? 2 + int(random() % 2) : 1;
  for (int edit = 0; edit < edits; ++edit) {
    switch (random() % 7) {
      case 0:  // delete a run of bytes
        if (!text.empty()) {
          const std::size_t at = below(text.size());
          text.erase(at, 1 + below(16));
        }
        break;
      case 1:  // insert punctuation
        text.insert(below(text.size() + 1), 1 + below(4), punctuation[below(punctuation.size())]);
        break;
      case 2: {  // replace a number with an extreme one
        std::vector<std::size_t> starts;
        for (std::size_t k = 0; k < text.size(); ++k)
          if (std::isdigit(static_cast<unsigned char>(text[k])) && (k == 0 || !std::isalnum(static_cast<unsigned char>(text[k - 1]))))
            starts.push_back(k);
        if (starts.empty()) break;
        const std::size_t at = starts[below(starts.size())];
        std::size_t end = at;
        while (end < text.size() && std::string("0123456789.e+-").find(text[end]) != std::string::npos) ++end;
        text.replace(at, end - at, extremes[below(extremes.size())]);
        break;
      }
      case 3: {  // duplicate a line
        auto lines = linesOf(text);
        if (lines.empty()) break;
        const std::size_t at = below(lines.size());
        lines.insert(lines.begin() + at, lines[at]);
        text.clear();
        for (const auto& line : lines) text += line + "\n";
        break;
      }
      case 4: {  // swap two lines
        auto lines = linesOf(text);
        if (lines.size() < 2) break;
        std::swap(lines[below(lines.size())], lines[below(lines.size())]);
        text.clear();
        for (const auto& line : lines) text += line + "\n";
        break;
      }
      case 5:  // truncate
        text.resize(below(text.size() + 1));
        break;
      default:  // flip a byte
        if (!text.empty()) text[below(text.size())] = char(random() % 256);
        break;
    }
  }
  return text;
}

void expectUserTermsOnly(const std::string& message, const std::string& source, const std::string& input) {
  EXPECT_EQ(message.rfind(source, 0), 0u) << message << "\n--- input:\n" << input;
  for (const char* internal : {"Teuchos", "any_cast", "YAMLParameterList", "::", ".cpp", ".hpp", "bug in", "Throw",
                               "/root", "typeid", "RCP", "Kokkos", "basic_string", "std::"})
    // Quoting the user's own text back is fine: only what the input does not hold is internal.
    if (input.find(internal) == std::string::npos)
      EXPECT_EQ(message.find(internal), std::string::npos) << "'" << internal << "' in: " << message
                                                           << "\n--- input:\n" << input;
}

// Model sizes a mutation can ask for are bounded here, not by the reader (a 1e8-node plate is a
// valid deck): models estimated over 20,000 nodes are only parsed.
bool smallEnoughToBuild(const perishell::Deck& deck, const perishell::Deck& seed) {
  const auto& mesh = deck.mesh;
  if (!(mesh.spacing > 0.0) || !(mesh.spacing >= 0.25 * seed.mesh.spacing)) return false;
  const double area = mesh.lengthX * mesh.lengthY + 2 * 3.14159265358979323846 * mesh.radius * mesh.height +
                      6 * mesh.side * mesh.length;
  return std::isfinite(area) && area / (mesh.spacing * mesh.spacing) <= 20000.0 &&
         deck.peridynamics.horizonFactor <= 2.0 * seed.peridynamics.horizonFactor;
}

TEST(TEST_CATEGORY, fuzzed_decks_end_in_a_model_or_a_message_in_the_users_terms) {
  std::vector<fs::path> seeds = {testDataDirectory / "decks" / "gmsh_plate.yaml"};
  for (const auto& entry : fs::directory_iterator(testDataDirectory / "decks" / "run"))
    if (entry.path().extension() == ".yaml") seeds.push_back(entry.path());
  std::sort(seeds.begin(), seeds.end());
  std::mt19937_64 random(20261203);
  int inputs = 0, refused = 0, built = 0;
  for (const auto& seedPath : seeds) {
    const std::string seedText = readText(seedPath);
    const perishell::Deck seedDeck = perishell::parseDeck(seedText, seedPath.string());
    for (int k = 0; k < 500; ++k, ++inputs) {
      const std::string text = mutate(seedText, random);
      try {
        const perishell::Deck deck = perishell::parseDeck(text, seedPath.string());
        if (smallEnoughToBuild(deck, seedDeck)) {
          perishell::model::buildModel(deck);
          ++built;
        }
      } catch (const std::exception& error) {
        ++refused;
        expectUserTermsOnly(error.what(), seedPath.string(), text);
      }
    }
  }
  std::printf("fuzzed decks: %d inputs from %zu seeds, %d refused, %d models built\n", inputs, seeds.size(), refused,
              built);
  EXPECT_GT(refused, inputs / 10);  // the mutations do reach the checks
  EXPECT_GT(built, inputs / 20);    // and many still make models
}

TEST(TEST_CATEGORY, fuzzed_gmsh_files_end_in_a_mesh_or_a_file_line_message) {
  const std::string seed = readText(testDataDirectory / "plate_4x2.msh");
  std::mt19937_64 random(7);
  int refused = 0;
  const int inputs = 10000;
  for (int k = 0; k < inputs; ++k) {
    const std::string text = mutate(seed, random);
    try {
      perishell::mesh::parseGmsh(text, "fuzz.msh");
    } catch (const std::exception& error) {
      ++refused;
      expectUserTermsOnly(error.what(), "fuzz.msh:", text);
    }
  }
  std::printf("fuzzed Gmsh files: %d inputs, %d refused\n", inputs, refused);
  EXPECT_GT(refused, inputs / 2);
}

}  // namespace fuzz_inputs_test
