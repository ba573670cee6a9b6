// How Lichtblick (and the last open-source Foxglove Studio) turns an MCAP channel into something it can
// plot: ported from lichtblick-suite/lichtblick, packages/mcap-support/src/ (commit 66adecb, MPL-2.0):
// parseChannel.ts (the dispatch on message encoding), parseJsonSchema.ts (which JSON schemas it takes:
// every field's "type" one string of boolean, string, number, integer, object or array; anything else,
// ["number", "null"] among them, throws) and parseProtobufSchema.ts (protobufjs reads the
// FileDescriptorSet with keepCase; messages decode with defaults and 64-bit integers as BigInt).
// Only the parts that decide accept or reject and what a message decodes to are kept.
import protobufjs from "protobufjs";
import "protobufjs/ext/descriptor/index.js";

const PRIMITIVE = { boolean: "bool", string: "string", number: "float64" };

function integerType(schema) {
  const nonNegative = (typeof schema.minimum === "number" && schema.minimum >= 0)
    || (typeof schema.exclusiveMinimum === "number" && schema.exclusiveMinimum >= 0);
  return nonNegative ? "uint32" : "int32";
}

// parseJsonSchema.ts: the datatypes of a JSON schema, or an Error as Lichtblick throws it.
export function parseJsonSchema(schema, typeName, keyPath = [], datatypes = new Map()) {
  if (schema.type !== "object") {
    throw new Error(`Expected "type": "object" for schema ${typeName}, got ${JSON.stringify(schema.type)}`);
  }
  const fields = [];
  for (const [name, field] of Object.entries(schema.properties ?? {})) {
    const path = keyPath.concat(name).join(".");
    if (Array.isArray(field.oneOf)) {
      if (!field.oneOf.every((alternative) => typeof alternative.const === "number")) {
        throw new Error(`Unsupported type for ${path}: oneOf alternatives must have number values`);
      }
      fields.push({ name, type: "uint32" });
      continue;
    }
    if (field.type === "string" && field.contentEncoding !== undefined && field.contentEncoding !== "base64") {
      throw new Error(`Unsupported contentEncoding ${JSON.stringify(field.contentEncoding)} in ${path}`);
    }
    if (field.type in PRIMITIVE) {
      fields.push({ name, type: PRIMITIVE[field.type] });
    } else if (field.type === "integer") {
      fields.push({ name, type: integerType(field) });
    } else if (field.type === "object") {
      parseJsonSchema(field, `${typeName}.${name}`, keyPath.concat(name), datatypes);
      fields.push({ name, type: `${typeName}.${name}`, isComplex: true });
    } else if (field.type === "array") {
      const item = field.items;
      if (item.type in PRIMITIVE && item.contentEncoding === undefined) {
        fields.push({ name, type: PRIMITIVE[item.type], isArray: true });
      } else if (item.type === "integer") {
        fields.push({ name, type: integerType(item), isArray: true });
      } else if (item.type === "object") {
        parseJsonSchema(item, `${typeName}.${name}`, keyPath.concat(name), datatypes);
        fields.push({ name, type: `${typeName}.${name}`, isComplex: true, isArray: true });
      } else {
        throw new Error(`Unsupported type ${JSON.stringify(item.type)} for array item ${path}`);
      }
    } else {
      throw new Error(`Unsupported type ${JSON.stringify(field.type)} for ${path}`);
    }
  }
  datatypes.set(typeName, { definitions: fields });
  return datatypes;
}

// parseProtobufSchema.ts: the root type of a FileDescriptorSet and a deserializer.
function parseProtobufSchema(schemaName, data) {
  const root = protobufjs.Root.fromDescriptor(data, { keepCase: true });
  root.resolveAll();
  const type = root.lookupType(schemaName);
  const datatypes = new Map([[schemaName, { definitions: type.fieldsArray.map((f) => ({ name: f.name, type: f.type })) }]]);
  const deserialize = (bytes) => type.toObject(type.decode(bytes), { defaults: true, longs: BigInt });
  return { datatypes, deserialize };
}

// parseChannel.ts: { datatypes, deserialize } of a channel, or an Error.
export function parseChannel(channel) {
  const decoder = new TextDecoder();
  if (channel.messageEncoding === "json") {
    if (channel.schema !== undefined && channel.schema.encoding !== "jsonschema") {
      throw new Error(`Message encoding json with schema encoding '${channel.schema.encoding}' is not supported`);
    }
    const schema = channel.schema && channel.schema.data.length > 0 ? JSON.parse(decoder.decode(channel.schema.data)) : undefined;
    const datatypes = schema === undefined ? new Map() : parseJsonSchema(schema, channel.schema.name);
    return { datatypes, deserialize: (bytes) => JSON.parse(decoder.decode(bytes)) };
  }
  if (channel.messageEncoding === "protobuf") {
    if (channel.schema?.encoding !== "protobuf") {
      throw new Error(`Message encoding protobuf with schema encoding '${channel.schema?.encoding}' is not supported`);
    }
    return parseProtobufSchema(channel.schema.name, channel.schema.data);
  }
  throw new Error(`Message encoding ${channel.messageEncoding} is not one the tests port`);
}
