// Types of contract.mjs, for the dashboard's TypeScript tests.
export declare const SCHEMA_FILE: string;
export interface Contract {
  /** The names of the contract's definitions. */
  names: string[];
  /** null when `value` is a valid `name`, else the first error with its path. */
  check(name: string, value: unknown): string | null;
}
export declare function contract(schemaText?: string): Contract;
