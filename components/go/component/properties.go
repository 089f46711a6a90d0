package component

import (
	"fmt"
	"math"
	"sort"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// Properties is the typed map configuring a new instance. A class reads
// the keys it knows with the getters below, each taking the value to use
// when the key is absent. Properties remembers which keys were read, so
// that Create can reject a key no getter asked for (a misspelling), and
// keeps the first error (a mistyped or invalid value), so that a
// constructor reads everything and need not check each getter.
type Properties struct {
	values map[string]*yarfv1.Property
	read   map[string]bool
	err    error
}

// PropertyError is what is wrong with one property.
type PropertyError struct {
	Key     string
	Problem string // e.g. "is missing", "must be of type rgb or float, not string"
}

func (e *PropertyError) Error() string {
	return fmt.Sprintf("property '%s' %s", e.Key, e.Problem)
}

// NewProperties wraps the proto map; nil is an empty map.
func NewProperties(properties *yarfv1.Properties) *Properties {
	return &Properties{values: properties.GetValues(), read: map[string]bool{}}
}

// Err is the first error a getter met, or nil.
func (p *Properties) Err() error { return p.err }

// Fail records a problem with a property found by the class itself (a
// value out of range, two properties that contradict each other), unless
// an error is already kept.
func (p *Properties) Fail(key, problem string) {
	if p.err == nil {
		p.err = &PropertyError{Key: key, Problem: problem}
	}
}

// Has reports whether key is set. It does not count as reading it.
func (p *Properties) Has(key string) bool {
	_, ok := p.values[key]
	return ok
}

// Require fails when key is absent: for properties without a default.
func (p *Properties) Require(key string) {
	if !p.Has(key) {
		p.Fail(key, "is missing")
	}
}

// Unread lists, sorted, the keys set that no getter read.
func (p *Properties) Unread() []string {
	var keys []string
	for key := range p.values {
		if !p.read[key] {
			keys = append(keys, key)
		}
	}
	sort.Strings(keys)
	return keys
}

// Float reads a real number; an int is accepted too.
func (p *Properties) Float(key string, fallback float64) float64 {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_FloatValue:
		return v.FloatValue
	case *yarfv1.Property_IntValue:
		return float64(v.IntValue)
	default:
		return mistyped(p, key, "float", v, fallback)
	}
}

// Int reads a signed integer.
func (p *Properties) Int(key string, fallback int64) int64 {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_IntValue:
		return v.IntValue
	default:
		return mistyped(p, key, "int", v, fallback)
	}
}

// Bool reads a switch.
func (p *Properties) Bool(key string, fallback bool) bool {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_BoolValue:
		return v.BoolValue
	default:
		return mistyped(p, key, "bool", v, fallback)
	}
}

// String reads text.
func (p *Properties) String(key string, fallback string) string {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_StringValue:
		return v.StringValue
	default:
		return mistyped(p, key, "string", v, fallback)
	}
}

// Reference reads the name of another object (or a handle as text).
func (p *Properties) Reference(key string, fallback string) string {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_Reference:
		return v.Reference
	default:
		return mistyped(p, key, "reference", v, fallback)
	}
}

// Vec3 reads a position or direction.
func (p *Properties) Vec3(key string, fallback [3]float64) [3]float64 {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_Vec3Value:
		return [3]float64{v.Vec3Value.GetX(), v.Vec3Value.GetY(), v.Vec3Value.GetZ()}
	default:
		return mistyped(p, key, "vec3", v, fallback)
	}
}

// Color reads linear RGB; a float f is accepted as the grey (f, f, f).
func (p *Properties) Color(key string, fallback [3]float64) [3]float64 {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_RgbValue:
		return [3]float64{v.RgbValue.GetR(), v.RgbValue.GetG(), v.RgbValue.GetB()}
	case *yarfv1.Property_FloatValue:
		return [3]float64{v.FloatValue, v.FloatValue, v.FloatValue}
	default:
		return mistyped(p, key, "rgb or float", v, fallback)
	}
}

// Reflectance reads a Color whose every channel lies in [0, 1].
func (p *Properties) Reflectance(key string, fallback [3]float64) [3]float64 {
	rgb := p.Color(key, fallback)
	for _, c := range rgb {
		if !(c >= 0 && c <= 1) {
			p.Fail(key, "must lie in [0, 1] in every channel")
			return fallback
		}
	}
	return rgb
}

// Transform reads a 4x4 row-major matrix of 16 finite values.
func (p *Properties) Transform(key string, fallback [16]float64) [16]float64 {
	switch v := p.lookup(key).(type) {
	case nil:
		return fallback
	case *yarfv1.Property_TransformValue:
		m := v.TransformValue.GetM()
		if len(m) != 16 {
			p.Fail(key, fmt.Sprintf("needs 16 values, got %d", len(m)))
			return fallback
		}
		var out [16]float64
		for i, x := range m {
			if math.IsNaN(x) || math.IsInf(x, 0) {
				p.Fail(key, "has a non-finite value")
				return fallback
			}
			out[i] = x
		}
		return out
	default:
		return mistyped(p, key, "transform", v, fallback)
	}
}

// lookup marks key read and returns its value, nil when absent. A key set
// with no value at all is an error.
func (p *Properties) lookup(key string) any {
	property, ok := p.values[key]
	if !ok {
		return nil
	}
	p.read[key] = true
	if property.GetValue() == nil {
		p.Fail(key, "has no value")
		return nil
	}
	return property.GetValue()
}

// mistyped records that key holds another type than wanted and returns
// the fallback, so the getter's caller goes on with a sane value.
func mistyped[T any](p *Properties, key, wanted string, value any, fallback T) T {
	p.Fail(key, fmt.Sprintf("must be of type %s, not %s", wanted, kindOf(value)))
	return fallback
}

// kindOf names a property value's type as the getters do.
func kindOf(value any) string {
	switch value.(type) {
	case *yarfv1.Property_FloatValue:
		return "float"
	case *yarfv1.Property_IntValue:
		return "int"
	case *yarfv1.Property_BoolValue:
		return "bool"
	case *yarfv1.Property_StringValue:
		return "string"
	case *yarfv1.Property_Vec3Value:
		return "vec3"
	case *yarfv1.Property_RgbValue:
		return "rgb"
	case *yarfv1.Property_TransformValue:
		return "transform"
	case *yarfv1.Property_Reference:
		return "reference"
	case *yarfv1.Property_FloatArrayValue:
		return "float array"
	default:
		return fmt.Sprintf("%T", value)
	}
}
