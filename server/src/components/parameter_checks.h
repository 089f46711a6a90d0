// Properties checked against a class's declared parameters (yarf/parameters.h),
// before anything is made of them: at Submit for every component a scene
// names, and at Factory.Create.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "yarf/component.h"
#include "yarf/v1/component.pb.h"

namespace yarf {

// Throws Error for the first property of `properties` that `info` does not
// declare (with the nearest declared name), whose kind its type does not
// take, or whose value lies outside its range or choices; and for a
// required parameter left out. `where` names the properties
// ("scene.materials[0] ('red').properties"). Nothing is checked for a
// class that declares no parameters.
void CheckProperties(const ComponentInfo& info, const v1::Properties& properties, const std::string& where);

// Throws Error for a schema a class or a component process declares that
// could not be checked against: an empty or repeated name, a default of
// another type than its parameter, bounds the wrong way round; or for a
// capability that is not one of kCapabilities.
void CheckSchema(const ComponentInfo& info);

// The entry of `candidates` nearest to `name` in edit distance, if near
// enough to be a misspelling of it; empty otherwise.
std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace yarf
