#include "cli/method_dispatch.hpp"

#include <string>

#include "core/error.hpp"

#if HFBAKE_HAVE_P1
#include "methods/p1/bake_p1.hpp"
#endif
#if HFBAKE_HAVE_P2
#include "methods/p2/bake_p2.hpp"
#endif
#if HFBAKE_HAVE_NLP
#include "methods/nlp/bake_nlp.hpp"
#endif
#if HFBAKE_HAVE_AO
#include "methods/ao/bake_ao.hpp"
#endif
#if HFBAKE_HAVE_REFERENCE
#include "reference/bake_reference.hpp"
#endif

namespace hfbake {

LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc) {
  const std::string& m = entry.method;
#if HFBAKE_HAVE_P1
  if (m == "p1") return bake_p1(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_P2
  if (m == "p2") return bake_p2(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_NLP
  if (m == "nlp") return bake_nlp(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_AO  // each obscurance method lands on its own (baker/methods/ao/CMakeLists.txt)
#if HFBAKE_HAVE_HBAO
  if (m == "hbao") return bake_hbao(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_LSAO
  if (m == "lsao") return bake_lsao(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_FARFIELD
  if (m == "farfield") return bake_farfield(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_HSAO
  if (m == "hsao") return bake_hsao(scene, entry.params, rc);
#endif
#if HFBAKE_HAVE_VO
  if (m == "vo") return bake_vo(scene, entry.params, rc);
#endif
#endif
  (void)scene;
  (void)rc;
  throw InputError("", entry.pointer + "/method", "method \"" + m + "\" is not available in this build");
}

LayerSet run_reference(const Job& job, const Scene& scene, const RunControl& rc) {
#if HFBAKE_HAVE_REFERENCE
  return bake_reference(scene, job.doc, rc);
#else
  (void)scene;
  (void)rc;
  throw InputError(job.file.string(), "/reference", "the reference is not available in this build");
#endif
}

}  // namespace hfbake
