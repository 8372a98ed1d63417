// The SVG renderer (csp/io/svg_plot.hpp) and the figures the shipped commands write: read back from
// the SVG itself. A limit chart's axis ends at the limit; no two texts' estimated boxes overlap; every
// text (titles included) lies inside its figure; every file is well-formed XML.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "csp/io/svg_plot.hpp"

namespace {

namespace fs = std::filesystem;

struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;   // a <text>'s content, entities resolved
};

std::string unescape(std::string s) {
  const std::pair<const char*, const char*> entities[] = {
      {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&apos;", "'"}, {"&amp;", "&"}};
  for (const auto& [entity, plain] : entities)
    for (std::size_t at; (at = s.find(entity)) != std::string::npos;) s.replace(at, std::string(entity).size(), plain);
  return s;
}

// A minimal XML reader for what an SVG file holds: elements with quoted attributes, text, a
// declaration. Fails the test (and returns what it read) on an unbalanced tag, an unquoted
// attribute, a stray '<' or '&' in text, or a second root.
std::vector<Element> parse_svg(const std::string& xml, const std::string& what) {
  std::vector<Element> elements;
  std::vector<std::string> open;
  int roots = 0;
  std::size_t i = 0;
  if (xml.starts_with("<?xml")) i = xml.find("?>") + 2;
  while (i < xml.size()) {
    const std::size_t lt = xml.find('<', i);
    const std::string between = xml.substr(i, lt == std::string::npos ? std::string::npos : lt - i);
    for (std::size_t amp = between.find('&'); amp != std::string::npos; amp = between.find('&', amp + 1))
      EXPECT_TRUE(std::regex_search(between.substr(amp, 6), std::regex("^&(amp|lt|gt|quot|apos);")))
          << what << ": a bare '&' in text";
    if (!open.empty() && open.back() == "text" && !elements.empty()) elements.back().text += unescape(between);
    if (lt == std::string::npos) {
      EXPECT_TRUE(between.find_first_not_of(" \n") == std::string::npos) << what << ": text after the root";
      break;
    }
    const std::size_t gt = xml.find('>', lt);
    if (gt == std::string::npos) {
      ADD_FAILURE() << what << ": an unclosed tag";
      break;
    }
    std::string tag = xml.substr(lt + 1, gt - lt - 1);
    if (tag.starts_with("/")) {
      const std::string name = tag.substr(1);
      if (open.empty() || open.back() != name) {
        ADD_FAILURE() << what << ": </" << name << "> closes " << (open.empty() ? "nothing" : open.back());
        break;
      }
      open.pop_back();
    } else {
      const bool empty = tag.ends_with("/");
      if (empty) tag.pop_back();
      Element e;
      std::istringstream in(tag);
      in >> e.name;
      // name="value" or name='value', separated by white space.
      std::string rest = tag.substr(e.name.size());
      for (std::size_t at = rest.find_first_not_of(" \n"); at != std::string::npos;
           at = rest.find_first_not_of(" \n")) {
        const std::size_t equals = rest.find('=', at);
        if (equals == std::string::npos || equals + 1 >= rest.size() || (rest[equals + 1] != '"' && rest[equals + 1] != '\''))
          break;
        const std::size_t close = rest.find(rest[equals + 1], equals + 2);
        if (close == std::string::npos) break;
        const std::string value = rest.substr(equals + 2, close - equals - 2);
        EXPECT_EQ(value.find('<'), std::string::npos) << what;
        e.attributes[rest.substr(at, equals - at)] = unescape(value);
        rest = rest.substr(close + 1);
      }
      EXPECT_TRUE(rest.find_first_not_of(" \n") == std::string::npos) << what << ": cannot read <" << tag << ">";
      if (open.empty()) ++roots;
      elements.push_back(e);
      if (!empty) open.push_back(e.name);
    }
    i = gt + 1;
  }
  EXPECT_TRUE(open.empty()) << what << ": " << open.size() << " elements left open";
  EXPECT_EQ(roots, 1) << what;
  EXPECT_FALSE(elements.empty() || elements.front().name != "svg") << what << ": the root is not <svg>";
  return elements;
}

double number_attribute(const Element& e, const std::string& name) {
  const auto it = e.attributes.find(name);
  if (it == e.attributes.end()) {
    ADD_FAILURE() << "<" << e.name << "> without " << name;
    return NAN;
  }
  return std::stod(it->second);
}

struct Box {
  double left, top, right, bottom;
  std::string text;
};

// A text's box from its position, anchor, size and estimated width: the glyphs rise 0.8 of the size
// above the baseline and descend 0.2 below it; rotate(-90 x y) turns it about its anchor point.
Box text_box(const Element& e) {
  const double x = number_attribute(e, "x"), y = number_attribute(e, "y"), size = number_attribute(e, "font-size");
  const double width = csp::estimated_text_width(e.text, size);
  const std::string anchor = e.attributes.count("text-anchor") ? e.attributes.at("text-anchor") : "start";
  const double start = anchor == "middle" ? -width / 2 : anchor == "end" ? -width : 0.0;
  if (e.attributes.count("transform")) {
    EXPECT_EQ(e.attributes.at("transform"), csp::format("rotate(-90 %.1f %.1f)", x, y)) << e.text;
    return {x - 0.8 * size, y - start - width, x + 0.2 * size, y - start, e.text};
  }
  return {x + start, y - 0.8 * size, x + start + width, y + 0.2 * size, e.text};
}

// Every text inside the figure, and no two overlapping (by more than half a pixel either way).
void expect_laid_out(const std::string& svg, const std::string& what) {
  const std::vector<Element> elements = parse_svg(svg, what);
  if (elements.empty()) return;
  const double width = number_attribute(elements.front(), "width"), height = number_attribute(elements.front(), "height");
  std::vector<Box> boxes;
  for (const Element& e : elements)
    if (e.name == "text" && !e.text.empty()) boxes.push_back(text_box(e));
  ASSERT_FALSE(boxes.empty()) << what;
  for (const Box& b : boxes) {
    EXPECT_GE(b.left, -0.5) << what << ": \"" << b.text << "\" sticks out on the left";
    EXPECT_LE(b.right, width + 0.5) << what << ": \"" << b.text << "\" sticks out on the right (" << b.right << " > "
                                    << width << ")";
    EXPECT_GE(b.top, -0.5) << what << ": \"" << b.text << "\" sticks out at the top";
    EXPECT_LE(b.bottom, height + 0.5) << what << ": \"" << b.text << "\" sticks out at the bottom";
  }
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t k = i + 1; k < boxes.size(); ++k) {
      const Box &a = boxes[i], &b = boxes[k];
      const bool overlap = std::min(a.right, b.right) - std::max(a.left, b.left) > 0.5 &&
                           std::min(a.bottom, b.bottom) - std::max(a.top, b.top) > 0.5;
      EXPECT_FALSE(overlap) << what << ": \"" << a.text << "\" overlaps \"" << b.text << "\"";
    }
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<Element> elements_named(const std::vector<Element>& all, const std::string& name) {
  std::vector<Element> out;
  for (const Element& e : all)
    if (e.name == name) out.push_back(e);
  return out;
}

TEST(SvgPlot, LimitChartsAxisEndsAtTheLimit) {
  const std::vector<double> fractions{0.5, 1.0, 1.4, 0.0, 0.25, 0.75, 0.1};
  const std::string svg = csp::render_panels("usage", {csp::joint_limit_panel("velocity", fractions)}, 1);
  expect_laid_out(svg, "the limit chart");
  const std::vector<Element> all = parse_svg(svg, "the limit chart");

  // The plot's frame, and the bars in the joints' order (filled rectangles inside the frame).
  const Element* frame = nullptr;
  std::vector<Element> bars;
  const std::vector<Element> rects = elements_named(all, "rect");   // kept: `frame` points into it
  for (const Element& e : rects) {
    if (e.attributes.count("stroke") && e.attributes.at("fill") == "none") frame = &e;
    else if (e.attributes.count("x")) bars.push_back(e);
  }
  ASSERT_NE(frame, nullptr);
  ASSERT_EQ(bars.size(), fractions.size());
  const double left = number_attribute(*frame, "x"), width = number_attribute(*frame, "width");
  for (std::size_t j = 0; j < fractions.size(); ++j) {
    EXPECT_NEAR(number_attribute(bars[j], "x"), left, 0.11) << "joint " << j + 1;
    EXPECT_NEAR(number_attribute(bars[j], "width"), std::min(fractions[j], 1.0) * width, 0.11) << "joint " << j + 1;
  }
  // Beyond the limit: drawn to the axis' end in another colour than the bars within it.
  EXPECT_NE(bars[2].attributes.at("fill"), bars[0].attributes.at("fill"));
  EXPECT_EQ(bars[1].attributes.at("fill"), bars[0].attributes.at("fill"));

  // The limit line at the axis' end, and the last tick there is the limit: 100 %.
  bool limit_line = false;
  for (const Element& e : elements_named(all, "line"))
    limit_line = limit_line || (std::abs(number_attribute(e, "x1") - (left + width)) < 0.11 &&
                                std::abs(number_attribute(e, "x2") - (left + width)) < 0.11 &&
                                e.attributes.count("stroke-dasharray"));
  EXPECT_TRUE(limit_line);
  double last_tick = -1.0, last_tick_x = 0.0;
  std::size_t over_marks = 0;
  for (const Element& e : elements_named(all, "text")) {
    std::smatch m;
    if (std::regex_match(e.text, m, std::regex(R"((\d+) %)")) && std::stod(m[1]) > last_tick)
      last_tick = std::stod(m[1]), last_tick_x = number_attribute(e, "x");
    if (e.text.find("over") != std::string::npos && e.text != "over the limit") {
      ++over_marks;
      EXPECT_EQ(e.text.find("140"), 0u) << e.text;   // the value beyond the limit, in per cent of it
    }
  }
  EXPECT_EQ(last_tick, 100.0);
  EXPECT_NEAR(last_tick_x, left + width, 0.11);
  EXPECT_EQ(over_marks, 1u);
}

// Adversarial content: long titles, long labels, wide tick numbers, many legend entries, many bars.
TEST(SvgPlot, LongTextsWrapAndNothingOverlaps) {
  csp::PlotPanel lines{"a panel title far too long to fit on one line above a plot only four hundred pixels wide",
                       "time since the start of the motion of the arm along its path [s]",
                       "a long vertical axis label that wraps [N m]",
                       {},
                       {}};
  for (int s = 0; s < 6; ++s) {
    csp::PlotSeries series{csp::format("series number %d with a long legend entry", s + 1), "#1f77b4", {}, {}};
    for (int k = 0; k <= 200; ++k)
      series.x.push_back(1234.5 + 0.001 * k), series.y.push_back(-123456.789 + 1000.0 * std::sin(0.05 * k + s));
    lines.series.push_back(series);
  }
  csp::PlotPanel bars{"ranking", "fraction", "", {{"", "#2ca02c", {}, {}}}, {}};
  for (int k = 0; k < 13; ++k) {
    bars.series[0].y.push_back(0.05 * k);
    bars.bar_labels.push_back(csp::format("effect_with_a_long_name_%d %.1f%% *", k, 5.0 * k));
  }
  const std::string title =
      "ultrasound_abdomen: depth along the tool axis (below the skin line, burr entry, trocar), and more words";
  expect_laid_out(csp::render_panels(title, {lines}, 1), "one column");
  expect_laid_out(csp::render_panels(title, {lines, bars, lines}, 2), "two columns");
  expect_laid_out(csp::render_panels(csp::format("%s %s", title.c_str(), title.c_str()), {bars}, 1), "bars");
}

// A long run's time series: a few points per pixel column, its peaks kept (a spike of one sample).
TEST(SvgPlot, DenseTimeSeriesKeepsItsPeaks) {
  csp::PlotSeries series{"", "#1f77b4", {}, {}};
  for (int k = 0; k < 100000; ++k) series.x.push_back(1e-3 * k), series.y.push_back(std::sin(1e-3 * k));
  series.y[61234] = 5.0, series.y[7000] = -3.0;
  const std::string svg = csp::render_panels("dense", {{"one", "t [s]", "y", {series}, {}}}, 1);
  const std::vector<Element> all = parse_svg(svg, "dense");
  const std::vector<Element> lines = elements_named(all, "polyline"), frames = elements_named(all, "rect");
  ASSERT_EQ(lines.size(), 1u);
  const Element& frame = frames.back();   // after the background
  std::istringstream points(lines[0].attributes.at("points"));
  double x = 0.0, y = 0.0, top = HUGE_VAL, bottom = -HUGE_VAL, top_x = 0.0, bottom_x = 0.0;
  std::size_t count = 0;
  for (char comma; points >> x >> comma >> y; ++count) {
    if (y < top) top = y, top_x = x;
    if (y > bottom) bottom = y, bottom_x = x;
  }
  const double left = number_attribute(frame, "x"), width = number_attribute(frame, "width");
  const double frame_top = number_attribute(frame, "y"), height = number_attribute(frame, "height");
  EXPECT_LE(count, static_cast<std::size_t>(2 * (width + 2)));
  // The axis spans [-3, 5] padded by 4 % each side; the spike at 5 and the dip at -3 are drawn there.
  const double span = 8.0 * 1.08;
  EXPECT_NEAR(top, frame_top + height * (0.04 * 8.0) / span, 0.11);
  EXPECT_NEAR(bottom, frame_top + height * (1.0 - 0.04 * 8.0 / span), 0.11);
  EXPECT_NEAR(top_x, left + width * 61.234 / 100.0, 1.0);   // the x axis reaches the tick at 100 s
  EXPECT_NEAR(bottom_x, left + width * 7.0 / 100.0, 1.0);
}

TEST(SvgPlot, HeatMapTextsFit) {
  csp::HeatMapFigure f;
  f.title = "panda workspace, side view: end effector (a gripper with a long name) position, seen from the side";
  f.subtitle = "1000000 uniform joint configurations, seed 1; circles centred on the shoulder (joint-2 origin), and "
               "a subtitle longer than the figure";
  f.x_label = "x [m]", f.y_label = "z [m]", f.colour_label = "samples per cell";
  f.x_min = -1.0, f.x_max = 1.0, f.y_min = -0.5, f.y_max = 1.3, f.nx = 40, f.ny = 36;
  f.counts.assign(40 * 36, 0);
  for (std::size_t i = 0; i < f.counts.size(); i += 3) f.counts[i] = i * 37 % 100000;
  f.circles = {{0, 0.333, 0.855, "sampled max reach from the shoulder 854.2 mm", "#111111", false},
               {0, 0.333, 0.855, "Franka datasheet reach 855 mm", "#d62728", true}};
  f.markers = {{0.0, 0.0, "base", csp::HeatMapMarker::Shape::kBase}};
  expect_laid_out(csp::render_heat_map(f), "heat map");
}

// The figures the shipped commands write: `csp emulate` of the default scenario (the set), a medical
// scenario's, `csp workspace`'s and `csp plan check`'s.
TEST(SvgPlot, ShippedCommandsFiguresAreLaidOut) {
  const fs::path dir = fs::temp_directory_path() / csp::format("csp_svg_plot_%d", static_cast<int>(::getpid()));
  fs::remove_all(dir);
  const std::string csp = CSP_EXECUTABLE, source = CSP_SOURCE_DIR;
  auto run = [&](const std::string& arguments, int exit_code = 0) {
    const std::string command = "cd " + source + " && " + csp + " " + arguments + " > /dev/null 2>&1";
    const int status = std::system(command.c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == exit_code) << command;
  };
  run("emulate configs/scenarios/default.yaml --duration 3 --report " + (dir / "emulate").string());
  run("emulate configs/scenarios/medical/laparoscopic_pivoting.yaml --duration 2 --report " + (dir / "medical").string());
  run("workspace --samples 20000 --out " + (dir / "workspace").string());
  run("plan check configs/scenarios/medical/plans/ultrasound_abdomen/trajectory.csv --scene ultrasound_abdomen "
      "--robot panda --out " + (dir / "plan").string(),
      1);   // the scan presses its probe on the patient: a failed clearance check, figures written

  const std::vector<std::string> emulate_set{"joint_positions.svg", "tracking_error.svg", "joint_torques.svg",
                                             "limits.svg", "ee_path.svg"};
  for (const std::string& name : emulate_set) EXPECT_TRUE(fs::exists(dir / "emulate" / name)) << name;
  for (const char* name : {"joint_positions.svg", "joint_torques.svg", "limits.svg", "ee_path.svg", "force.svg",
                                  "path.svg", "penetration.svg"})
    EXPECT_TRUE(fs::exists(dir / "medical" / name)) << name;
  EXPECT_FALSE(fs::exists(dir / "medical" / "tracking_error.svg"));   // a task, not a joint trajectory
  EXPECT_TRUE(fs::exists(dir / "plan" / "limits.svg"));

  int figures = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.path().extension() == ".svg") {
      ++figures;
      expect_laid_out(read_file(entry.path()), entry.path().string());
    }
  EXPECT_GE(figures, 17);
  fs::remove_all(dir);
}

}  // namespace
