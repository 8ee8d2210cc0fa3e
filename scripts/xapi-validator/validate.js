// Validates xAPI statements as a learning record store would: each statement of each FILE (a JSON
// array, as `anatomy-tutor xapi` writes) through Learning Locker's validator
// (@learninglocker/xapi-validation, installed by scripts/xapi-validator.sh), and every statement id
// and registration as an RFC 4122 UUID of versions 1-5, which the ADL conformance suite requires of
// an LRS (Learning Locker's validator checks only the variant).
//
//   node validate.js FILE.json...   one line per problem on stdout; exit status 1 when any, else 0
'use strict';
const fs = require('fs');
const validate = require('@learninglocker/xapi-validation').default;

const rfc4122 = /^[0-9a-f]{8}-[0-9a-f]{4}-[1-5][0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}$/i;
let problems = 0, statements = 0;
const report = (where, message) => {
  problems += 1;
  console.log(`${where}: ${message}`);
};
for (const file of process.argv.slice(2)) {
  let list;
  try {
    list = JSON.parse(fs.readFileSync(file, 'utf8'));
  } catch (e) {
    report(file, `not JSON: ${e.message}`);
    continue;
  }
  if (!Array.isArray(list)) {
    report(file, 'not a JSON array of statements');
    continue;
  }
  list.forEach((statement, i) => {
    statements += 1;
    const where = `${file}[${i}]`;
    for (const w of validate(statement)) report(where, `${(w.path || []).join('.')}: ${w.message} (${w.name})`);
    if (typeof statement.id !== 'string' || !rfc4122.test(statement.id)) report(where, `id ${statement.id} is not an RFC 4122 UUID (versions 1-5)`);
    const registration = statement.context && statement.context.registration;
    if (registration !== undefined && !rfc4122.test(registration))
      report(where, `context.registration ${registration} is not an RFC 4122 UUID (versions 1-5)`);
  });
}
console.log(`${statements} statement(s), ${problems} problem(s)`);
process.exit(problems > 0 ? 1 : 0);
