#include "cli/texture_plan.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "core/error.hpp"
#include "job/params.hpp"
#include "methods/method_table.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {

namespace {

// A bake output and the layers it writes (resolved), with their channel counts.
struct OutputLayers {
  std::string stem, method;
  std::map<std::string, int> channels;
};

std::vector<OutputLayers> job_outputs(const Job& job) {
  std::vector<OutputLayers> outs;
  auto add = [&](const std::string& stem, const std::string& method, const std::vector<std::string>& layers,
                 int directions) {
    OutputLayers o{stem, method, {}};
    for (const std::string& l : layers) o.channels[l] = layer_channel_count(l, directions);
    outs.push_back(std::move(o));
  };
  const std::vector<std::string> none;
  for (const BakeEntry& e : job.bakes)
    add(e.stem, e.method, e.config ? e.config->layers : none, e.config ? e.config->directions : 0);
  if (job.has_reference)
    add("reference", "reference", job.reference_options ? job.reference_options->layers : none, 0);
  outs.push_back({kHeightStem, kHeightStem, {{"normal", 3}}});
  return outs;
}

std::string list_layers(const OutputLayers& o) {
  std::string names;
  for (const auto& [name, n] : o.channels) names += (names.empty() ? "\"" : ", \"") + name + "\"";
  return o.stem + " writes " + (names.empty() ? std::string("nothing") : names);
}

struct Channel {
  std::string layer, suffix;  // layer empty: constant
  float constant = 0;
  std::string pointer;
};

// "ao" (a one-channel layer), "direct.R" (a channel of a layer) or a number in [0, 1].
Channel read_channel(const nlohmann::json& v, const std::string& pointer) {
  Channel c;
  c.pointer = pointer;
  if (v.is_number()) {
    c.constant = v.get<float>();
    return c;
  }
  const std::string s = v.get<std::string>();
  const auto dot = s.find('.');
  c.layer = s.substr(0, dot);
  if (dot != std::string::npos) c.suffix = s.substr(dot + 1);
  return c;
}

}  // namespace

std::vector<std::string> layer_suffixes(const std::string& layer, int channels) {
  if (is_direction_layer(layer)) return xyz_channels();
  if (channels == 1) return mono_channels();
  if (channels == 3) return rgb_channels();
  return indexed_channels(channels);
}

std::vector<PlannedTexture> plan_textures(const Job& job) {
  std::vector<PlannedTexture> plan;
  const nlohmann::json* list = nullptr;
  if (job.doc.contains("output") && job.doc["output"].contains("textures"))
    list = &job.doc["output"]["textures"];
  if (!list) return plan;
  const std::string file = job.file.string();
  const bool repeat = job.doc.contains("height") && job.doc["height"].value("wrap", "clamp") == "repeat";
  const std::vector<OutputLayers> outputs = job_outputs(job);
  std::map<std::string, std::string> written_by;  // file -> pointer of the entry writing it
  for (std::size_t i = 0; i < list->size(); ++i) {
    const nlohmann::json& t = (*list)[i];
    const std::string p = "/output/textures/" + std::to_string(i);
    auto fail = [&](const std::string& key, const std::string& what) {
      throw InputError(file, key.empty() ? p : p + "/" + key, what);
    };
    TextureSpec base;
    base.bits = t.value("bits", 8);
    const int padding = t.value("padding", 0);
    base.padding = repeat ? 0 : padding;
    base.repeat = repeat;
    base.exposure = t.value("exposure", 1.0);
    base.transfer = t.value("transfer", "linear") == "srgb" ? Transfer::srgb : Transfer::linear;
    const std::string format = t.value("format", "png");
    if (format == "tga" && base.bits == 16)
      fail("bits", "TGA holds 8 bits per channel; write 16 bits as \"png\" or \"tif\"");
    if (format == "exr" && t.contains("bits"))
      fail("bits", "an \"exr\" texture is half float; \"bits\" applies to png, tif and tga");
    if (format == "exr" && base.transfer == Transfer::srgb)
      fail("transfer", "an \"exr\" texture holds linear values; \"srgb\" applies to png, tif and tga");

    // What one file of this entry holds: a label (layer or pack name) and its channels.
    struct Content {
      std::string label;
      std::vector<Channel> channels;
      bool whole_layer = false;  // "layers": every channel of the layer
    };
    std::vector<Content> contents;
    bool has_direction = false;
    if (t.contains("layers")) {
      for (std::size_t k = 0; k < t["layers"].size(); ++k) {
        const std::string name = t["layers"][k].get<std::string>();
        Channel c;
        c.layer = name;
        c.pointer = p + "/layers/" + std::to_string(k);
        contents.push_back({name, {c}, true});
        has_direction = has_direction || is_direction_layer(name);
      }
    } else {
      Content pack{t["pack"].get<std::string>(), {}, false};
      const nlohmann::json& ch = t["channels"];
      for (const char* key : {"R", "G", "B", "A"}) {
        if (ch.contains(key)) {
          pack.channels.push_back(read_channel(ch[key], p + "/channels/" + key));
        } else if (std::string(key) != "A") {
          Channel zero;  // a missing R, G or B is 0
          pack.channels.push_back(zero);
        }
      }
      contents.push_back(pack);
    }
    if (!has_direction && (t.contains("space") || t.contains("y")))
      fail(t.contains("space") ? "space" : "y",
           "applies to bent_normal and normal, which this entry does not write");
    if (has_direction && t.contains("exposure"))
      fail("exposure", "applies to values (light maps), not to normal maps");
    base.space = t.value("space", "tangent") == "world" ? NormalSpace::world : NormalSpace::tangent;
    if (base.space == NormalSpace::world && t.contains("y"))
      fail("y",
           "world space has no green convention (G is hfbake's +y, image down); \"y\" applies to "
           "\"space\": \"tangent\"");
    base.green = t.value("y", "opengl") == "directx" ? GreenAxis::directx : GreenAxis::opengl;
    if (has_direction && base.transfer == Transfer::srgb)
      fail("transfer",
           "bent_normal and normal are directions: normal maps are encoded 0.5 + 0.5 n, never sRGB");

    // Which outputs: those "methods" names (stem or method), else every bake entry writing all the layers.
    std::vector<const OutputLayers*> targets;
    auto has_all = [&](const OutputLayers& o, std::string& missing) {
      for (const Content& c : contents)
        for (const Channel& ch : c.channels)
          if (!ch.layer.empty() && !o.channels.count(ch.layer)) {
            missing = ch.layer;
            return false;
          }
      return true;
    };
    if (t.contains("methods")) {
      for (std::size_t k = 0; k < t["methods"].size(); ++k) {
        const std::string want = t["methods"][k].get<std::string>();
        bool found = false;
        for (const OutputLayers& o : outputs) {
          if (o.stem != want && o.method != want) continue;
          found = true;
          std::string missing;
          if (!has_all(o, missing))
            fail("methods/" + std::to_string(k), "\"" + missing + "\" is not among its layers (" +
                                                     list_layers(o) + "; a method's \"layers\" picks them)");
          targets.push_back(&o);
        }
        if (!found) {
          std::vector<std::string> stems;
          for (const OutputLayers& o : outputs) stems.push_back(o.stem);
          fail("methods/" + std::to_string(k),
               "no bake output \"" + want + "\" in this job (" + quoted_list(stems) + ")");
        }
      }
    } else {
      // The height field's own output (its normal) only for a texture that reads one of its layers: a pack
      // of constants alone is every bake entry's, not also the height's.
      bool reads_a_layer = false;
      for (const Content& c : contents)
        for (const Channel& ch : c.channels) reads_a_layer = reads_a_layer || !ch.layer.empty();
      for (const OutputLayers& o : outputs) {
        std::string missing;
        if (o.stem != "reference" && (o.stem != kHeightStem || reads_a_layer) && has_all(o, missing))
          targets.push_back(&o);
      }
      if (targets.empty()) {
        // Name a layer no output writes, if there is one (a misspelt layer: "R": "1" for the number 1).
        std::string unwritten;
        for (const Content& c : contents)
          for (const Channel& ch : c.channels)
            if (unwritten.empty() && !ch.layer.empty() &&
                std::none_of(outputs.begin(), outputs.end(),
                             [&](const OutputLayers& o) { return o.channels.count(ch.layer) > 0; }))
              unwritten = ch.layer;
        std::string what = unwritten.empty()
                               ? "no bake entry writes every layer this texture reads ("
                               : "no bake entry writes \"" + unwritten + "\", which this texture reads (";
        for (std::size_t k = 0; k < outputs.size(); ++k) what += (k ? "; " : "") + list_layers(outputs[k]);
        fail("", what + "); add them to a method's \"layers\"");
      }
    }

    for (const OutputLayers* o : targets) {
      for (const Content& c : contents) {
        PlannedTexture pt;
        pt.stem = o->stem;
        pt.file = "textures/" + job.name + "." + o->stem + "." + c.label + "." + format;
        pt.spec = base;
        if (repeat && padding > 0)
          pt.note = pt.file + ": no padding added (the field repeats: the texture keeps its " +
                    "size and tiles as it is)";
        for (const Channel& ch : c.channels) {
          if (ch.layer.empty()) {
            pt.spec.channels.push_back({"", 0, ch.constant});
            pt.suffixes.emplace_back();
            continue;
          }
          const int n = o->channels.at(ch.layer);
          const std::vector<std::string> suffixes = layer_suffixes(ch.layer, n);
          if (c.whole_layer) {
            if (n != 1 && n != 3)
              throw InputError(file, ch.pointer,
                               "\"" + ch.layer + "\" has " + std::to_string(n) +
                                   " channels (one per direction or coefficient): a texture takes a "
                                   "scalar, a colour or bent_normal; pick channels with a pack, e.g. \"" +
                                   ch.layer + "." + suffixes[0] + "\"");
            for (int k = 0; k < n; ++k) {
              pt.spec.channels.push_back({ch.layer, 0, 0});
              pt.suffixes.push_back(suffixes[k]);
            }
            pt.spec.normal_map = is_direction_layer(ch.layer);
            continue;
          }
          std::string suffix = ch.suffix;
          if (suffix.empty()) {
            if (n != 1)
              throw InputError(file, ch.pointer,
                               "\"" + ch.layer + "\" has " + std::to_string(n) + " channels: name one (" +
                                   quoted_list({ch.layer + "." + suffixes[0]}) + ", ...)");
            suffix = suffixes[0];
          } else if (std::find(suffixes.begin(), suffixes.end(), suffix) == suffixes.end()) {
            throw InputError(file, ch.pointer,
                             "\"" + ch.layer + "\" has no channel \"" + suffix +
                                 "\" (its channels: " + quoted_list(suffixes) + ")");
          }
          pt.spec.channels.push_back({ch.layer, 0, 0});
          pt.suffixes.push_back(suffix);
        }
        const auto [it, fresh] = written_by.emplace(pt.file, p);
        if (!fresh)
          fail("", "writes " + pt.file + ", which " + it->second +
                       " writes too (give one of them other \"methods\", a \"pack\" name or a \"format\")");
        plan.push_back(std::move(pt));
      }
    }
  }
  return plan;
}

}  // namespace hfbake
